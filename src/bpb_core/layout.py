"""Where things live on disk: dataset and run folders mirror each other.

Dataset: ``DIR/dataset.json``, ``DIR/index.csv``, ``DIR/stats/``,
``DIR/h{t}/scene_{i:04d}/{init.json, final.json, init.png, final.png, trajectory.png}``.
Run: ``RUN_DIR/run.json``, ``RUN_DIR/attempts.jsonl``,
``RUN_DIR/h{t}/scene_{i:04d}/{task}.json``.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from bpb_core.errors import BadInput

MANIFEST = "dataset.json"
INDEX = "index.csv"
INIT = "init.json"
FINAL = "final.json"
RUN_MANIFEST = "run.json"
ATTEMPTS = "attempts.jsonl"
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
    taken: dict[float, int] = {}
    chosen: list[SceneKey] = []
    for key in keys:
        if wanted is not None and key.horizon not in wanted:
            continue
        if limit is not None and taken.get(key.horizon, 0) >= limit:
            continue
        taken[key.horizon] = taken.get(key.horizon, 0) + 1
        chosen.append(key)
    return chosen


def check_writable_folder(path: Path, option: str = "--out") -> None:
    """Check that ``path`` is, or can be created as, a folder this process can write.

    Raises:
        BadInput: ``path`` or an ancestor is a file, or the nearest existing ancestor is not
            writable (one line naming that path and ``option``).
    """
    from bpb_core.errors import BadInput

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
    work whose result would then be lost).

    Raises:
        BadInput: ``path`` is a folder or a file that cannot be written, or its folder cannot be
            (one line naming the path and ``option``).
    """
    from bpb_core.errors import BadInput

    if path.is_dir():
        raise BadInput(f"{path}: {option}: a folder, expected a file path")
    if path.exists() and not os.access(path, os.W_OK):
        raise BadInput(f"{path}: {option}: not writable")
    check_writable_folder(path.parent, option)


def make_folder(path: Path, option: str = "--out") -> None:
    """Create the folder ``path`` (and its parents) after :func:`check_writable_folder`.

    Raises:
        BadInput: It cannot be created or written (one line naming the path and ``option``).
    """
    from bpb_core.errors import BadInput

    check_writable_folder(path, option)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BadInput(f"{path}: {option}: cannot create the folder: {exc.strerror}") from None
