"""One ``bpb run`` per run folder at a time.

Two runs writing one folder would pay every call twice and interleave their answers. The first
run holds an exclusive ``flock`` on ``RUN_DIR/run.lock`` (holding its pid) until it ends; a second
run on the folder is refused as bad input naming the holder's pid. The operating system drops the
lock when its process dies, however it dies, so a lock left by a dead run is simply taken over.
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from bpb_core.errors import BadInput
from bpb_core.layout import RUN_LOCK


def _holder(handle: int) -> str:
    os.lseek(handle, 0, os.SEEK_SET)
    text = os.read(handle, 64).decode("ascii", "replace").strip()
    return text or "unknown"


@contextmanager
def run_lock(run_dir: Path) -> Iterator[None]:
    """Hold the run folder's lock for the block.

    Raises:
        BadInput: Another live process holds the folder (one line naming its pid), or the
            folder cannot hold a lock file (names the path).
    """
    path = run_dir / RUN_LOCK
    try:
        handle = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as exc:
        raise BadInput(f"{path}: cannot create the run lock: {exc.strerror or exc}") from None
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise BadInput(
                f"{run_dir}: in use by another bpb run (pid {_holder(handle)}); wait for it to "
                "finish or stop it, then re-run to resume"
            ) from None
        os.ftruncate(handle, 0)
        os.pwrite(handle, f"{os.getpid()}\n".encode("ascii"), 0)
        try:
            yield
        finally:
            os.ftruncate(handle, 0)
            fcntl.flock(handle, fcntl.LOCK_UN)
    finally:
        os.close(handle)
