"""The cache folders Inspect logs are read into (``$BPB_CACHE_DIR/inspect/``): one per set of
log folders, replaced when the logs change, shared by readers at the same time.

A folder is named ``<where>-<state>``: ``where`` names the logs' folders, ``state`` the logs as
they are (paths, sizes, modification times). It is built in a hidden temporary folder and
renamed into place whole, so a reader never sees half of one, and a reader finding it made uses
it. Every process using a folder holds a shared ``flock`` on it until it exits or reads a newer
state of the same logs (``bpb view`` reads answer files long after loading them). Once a
reader has its folder, the other states of its logs that no process holds are removed; the
system drops a dead process's locks, so what a killed reader held goes at the next reading.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import shutil
import tempfile
import threading
from collections.abc import Callable
from pathlib import Path

from bpb_core.dataset.hf_import import cache_root

PREFIX = "inspect"
_HELD: dict[str, int] = {}
"""Per ``where``: the descriptor holding this process's shared lock on its folder."""
_GUARD = threading.Lock()


def cache_folder(where: str, state: str, build: Callable[[Path], None]) -> Path:
    """The folder ``<where>-<state>`` under ``$BPB_CACHE_DIR/inspect``, made by ``build`` (given
    an empty folder) unless made already, and held by this process (see the module docstring).

    Raises:
        OSError: The folder keeps being removed while taken (other processes reading other
            states of the same logs, over and over).
    """
    base = cache_root() / PREFIX
    root = base / f"{where}-{state}"
    for _ in range(5):
        if not root.is_dir():
            _build(root, build)
        handle = _hold(root)
        if handle is not None:
            _keep(where, handle)
            _prune(base, where, root.name)
            return root
    raise OSError(f"{root}: removed each time it was made; try again")


def _build(root: Path, build: Callable[[Path], None]) -> None:
    root.parent.mkdir(parents=True, exist_ok=True)
    building = Path(tempfile.mkdtemp(prefix=f".{root.name}.", dir=root.parent))
    try:
        build(building)
        with contextlib.suppress(OSError):  # another caller made it meanwhile, from the same logs
            building.rename(root)  # whole or not at all
    finally:
        shutil.rmtree(building, ignore_errors=True)


def _hold(root: Path) -> int | None:
    """A descriptor of ``root`` with a shared lock on it; ``None`` when ``root`` was removed
    (or replaced) before the lock was taken."""
    try:
        handle = os.open(root, os.O_RDONLY | os.O_DIRECTORY)
    except FileNotFoundError:
        return None
    fcntl.flock(handle, fcntl.LOCK_SH)
    try:
        now, held = os.stat(root), os.fstat(handle)
        if (now.st_dev, now.st_ino) == (held.st_dev, held.st_ino):
            return handle
    except FileNotFoundError:
        pass
    os.close(handle)
    return None


def _keep(where: str, handle: int) -> None:
    """Hold ``handle``'s folder for the process, letting go of the one held before for these
    logs."""
    with _GUARD:
        before = _HELD.get(where)
        _HELD[where] = handle
    if before is not None:
        os.close(before)


def _prune(base: Path, where: str, keep: str) -> None:
    """Remove the other states of ``where`` that no process holds (each taken with an exclusive
    lock first, which fails while a reader holds it)."""
    for path in base.glob(f"{where}-*"):
        if path.name == keep:
            continue
        try:
            handle = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
        except OSError:
            continue  # removed by another reader meanwhile
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            gone = path.with_name(f".{path.name}.{os.getpid()}.gone")
            path.rename(gone)  # out of readers' sight before it is emptied
            shutil.rmtree(gone, ignore_errors=True)
        except OSError:  # in use (BlockingIOError), or taken by another reader
            continue
        finally:
            os.close(handle)
