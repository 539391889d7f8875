"""Hidden ``.NAME.partial`` folders that an output is built in before it is moved into place.

A command that writes a folder (a dataset, an export) builds it beside its target and moves it
in at the end, so a failure never leaves a half-made folder where a finished one is expected.
Two such commands on one target at once would share the partial folder, each clearing what the
other wrote; so the partial folder is held with an exclusive ``flock`` while it is built, and a
second command is refused as bad input. The system drops the lock when its process dies, so a
folder left by an interrupted command is simply emptied and reused.
"""

from __future__ import annotations

import fcntl
import os
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from bpb_core.errors import BadInput


def partial_path(target: Path) -> Path:
    """The hidden folder ``target`` is built in: ``.NAME.partial`` beside it."""
    where = Path(os.path.abspath(target))
    return where.parent / f".{where.name}.partial"


@contextmanager
def partial_folder(target: Path, command: str) -> Iterator[Path]:
    """Hold an empty partial folder for ``target`` for the block (the caller moves it in).

    Raises:
        BadInput: The folder cannot be made (names ``--out``), or another ``command`` is
            building ``target`` now.
    """
    partial = partial_path(target)
    handle = _open(partial, target)
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise BadInput(
                f"{target}: --out: another {command} is writing it now ({partial} is in use); "
                "wait for it to end, or choose another --out"
            ) from None
        for child in list(partial.iterdir()):  # left over from an interrupted command
            if child.is_dir() and not child.is_symlink():
                shutil.rmtree(child)
            else:
                child.unlink()
        yield partial
    finally:
        os.close(handle)


def _open(partial: Path, target: Path) -> int:
    """A descriptor of ``partial``, made if need be (once more if another command moved it
    away between the two steps)."""
    for _ in range(2):
        try:
            partial.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise BadInput(f"{target}: --out: cannot create the folder: {exc.strerror}") from None
        try:
            return os.open(partial, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
        except FileNotFoundError:
            continue
        except OSError as exc:
            raise BadInput(f"{partial}: cannot open the folder: {exc.strerror}") from None
    raise BadInput(f"{target}: --out: another command keeps moving {partial}; try again")
