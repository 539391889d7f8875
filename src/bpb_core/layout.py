"""Where things live on disk: dataset and run folders mirror each other.

Dataset: ``DIR/dataset.json``, ``DIR/index.csv``, ``DIR/stats/``, ``DIR/h{t}/scene_{i:04d}/``
(``init.json``, ``final.json``, the family's images). Run: ``RUN_DIR/run.json``,
``RUN_DIR/attempts.jsonl``, ``RUN_DIR/h{t}/scene_{i:04d}/{task}.json``.

A command that writes a folder (a dataset, an export) builds it in a hidden ``.NAME.partial``
folder beside its target and moves it in at the end, so a failure never leaves a half-made
folder. The partial folder is held with an exclusive ``flock`` while it is built, so a second
command on the same target is refused as bad input; one left by an interrupted command (the
system dropped its lock) is emptied and reused.
"""

from __future__ import annotations

import fcntl
import os
import re
import shutil
from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from bpb_core.errors import BadInput

MANIFEST = "dataset.json"
INDEX = "index.csv"
INIT = "init.json"
FINAL = "final.json"
RUN_MANIFEST = "run.json"
ATTEMPTS = "attempts.jsonl"
SPENDING = "spending.jsonl"
RUN_LOCK = "run.lock"
_SCENE_DIR = re.compile(r"^scene_(\d{4,})$")
_HORIZON_DIR = re.compile(r"^h(\d+(?:\.\d+)?)$")


def horizon_label(horizon: float) -> str:
    """``h3`` for 3.0 s, ``h2.5`` for 2.5 s."""
    return f"h{horizon:g}"


def scene_id(horizon: float, index: int) -> str:
    """The id of scene ``index`` at ``horizon``: ``h3_0007``."""
    return f"{horizon_label(horizon)}_{index:04d}"


def scene_dir(root: Path, horizon: float, index: int) -> Path:
    """``root/h{t}/scene_{i:04d}`` (the same shape in dataset and run folders)."""
    return root / horizon_label(horizon) / f"scene_{index:04d}"


@dataclass(frozen=True, order=True)
class SceneKey:
    """A scene's place in a dataset: horizon and index."""

    horizon: float
    index: int

    @property
    def scene_id(self) -> str:
        return scene_id(self.horizon, self.index)

    def dir(self, root: Path) -> Path:
        return scene_dir(root, self.horizon, self.index)


def iter_scene_keys(root: Path) -> Iterator[SceneKey]:
    """Every ``h{t}/scene_{i}`` folder under ``root``, sorted by horizon then index."""
    return (SceneKey(horizon, index) for horizon, index in scene_places(root))


def scene_places(root: Path) -> list[tuple[float, int]]:
    """:func:`iter_scene_keys` as plain ``(horizon, index)`` tuples (folders listed with
    ``os.scandir``, whose entries know they are folders without a ``stat`` each; sorted as
    tuples, not through the dataclass's ``__lt__``)."""
    found: list[tuple[float, int]] = []
    if not root.is_dir():
        return found
    with os.scandir(root) as hdirs:
        for hdir in hdirs:
            hmatch = _HORIZON_DIR.match(hdir.name)
            if not hmatch or not _is_dir(hdir):
                continue
            horizon = float(hmatch.group(1))
            with os.scandir(hdir.path) as sdirs:
                for sdir in sdirs:
                    smatch = _SCENE_DIR.match(sdir.name)
                    if smatch and _is_dir(sdir):
                        found.append((horizon, int(smatch.group(1))))
    found.sort()
    return found


def _is_dir(entry: os.DirEntry[str]) -> bool:
    """Whether a listed entry is a folder; a symbolic link that cannot be followed (a loop, a
    dangling target) is refused, named, rather than failing later without a name."""
    try:
        return entry.is_dir()
    except OSError as exc:
        raise BadInput(f"{entry.path}: cannot open: {exc.strerror or exc}") from None


def select_keys(
    keys: Iterable[SceneKey], horizons: Sequence[float] | None = None, limit: int | None = None
) -> list[SceneKey]:
    """``keys`` (sorted) at ``horizons`` (all when ``None``), the first ``limit`` per horizon:
    the one selection rule of runs, dry runs and the scoring of runs."""
    wanted = None if horizons is None else {float(h) for h in horizons}
    taken: Counter[float] = Counter()
    chosen: list[SceneKey] = []
    for key in keys:
        if wanted is not None and key.horizon not in wanted:
            continue
        if limit is None or taken[key.horizon] < limit:
            taken[key.horizon] += 1
            chosen.append(key)
    return chosen


def check_writable_folder(path: Path, option: str = "--out") -> None:
    """Check that ``path`` is, or can be created as, a folder this process can write; else a
    :class:`BadInput` naming ``option`` and the ancestor at fault (a file, or not writable)."""
    for parent in (path, *path.parents):
        if not parent.exists():
            continue
        if not parent.is_dir():
            raise BadInput(f"{parent}: {option}: not a folder (a file is in the way of {path})")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise BadInput(f"{parent}: {option}: not writable")
        return


def check_writable_file(path: Path, option: str) -> None:
    """Check that ``path`` is, or can be created as, a file this process can write (before any
    work whose result would then be lost); else a :class:`BadInput` naming it and ``option``."""
    if path.is_dir():
        raise BadInput(f"{path}: {option}: a folder, expected a file path")
    if path.exists() and not os.access(path, os.W_OK):
        raise BadInput(f"{path}: {option}: not writable")
    check_writable_folder(path.parent, option)


def partial_path(target: Path) -> Path:
    """The hidden folder ``target`` is built in: ``.NAME.partial`` beside it."""
    where = Path(os.path.abspath(target))
    return where.parent / f".{where.name}.partial"


@contextmanager
def partial_folder(target: Path, command: str) -> Iterator[Path]:
    """Hold an empty partial folder for ``target`` for the block (the caller moves it in); a
    :class:`BadInput` when it cannot be made (names ``--out``) or another ``command`` holds it."""
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
