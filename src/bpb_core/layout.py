"""Where things live on disk: dataset and run folders mirror each other.

Dataset: ``DIR/dataset.json``, ``DIR/index.csv``, ``DIR/stats/``,
``DIR/h{t}/scene_{i:04d}/{init.json, final.json, init.png, final.png, trajectory.png}``.
Run: ``RUN_DIR/run.json``, ``RUN_DIR/attempts.jsonl``,
``RUN_DIR/h{t}/scene_{i:04d}/{task}.json``.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

MANIFEST = "dataset.json"
INDEX = "index.csv"
INIT = "init.json"
FINAL = "final.json"
RUN_MANIFEST = "run.json"
ATTEMPTS = "attempts.jsonl"
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
    keys: list[SceneKey] = []
    if not root.is_dir():
        return iter(())
    for hdir in root.iterdir():
        hmatch = _HORIZON_DIR.match(hdir.name)
        if not hmatch or not hdir.is_dir():
            continue
        for sdir in hdir.iterdir():
            smatch = _SCENE_DIR.match(sdir.name)
            if smatch and sdir.is_dir():
                keys.append(SceneKey(float(hmatch.group(1)), int(smatch.group(1))))
    return iter(sorted(keys))


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
