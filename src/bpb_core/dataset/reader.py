"""Read a generated dataset: manifest, scene list and the scenes with their ground truth.

Scenes are read lazily, one folder at a time. Every corrupt or missing file raises
:class:`~bpb_core.errors.BadInput` naming the file (and the field, for JSON files).
"""

from __future__ import annotations

import csv
import hashlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from bpb_core.dataset.manifest import CHECKSUMS, DatasetManifest
from bpb_core.errors import BadInput
from bpb_core.layout import FINAL, INDEX, INIT, MANIFEST, SceneKey
from bpb_core.model_files import read_model
from bpb_core.scene import FinalState, Scene


@dataclass(frozen=True)
class Dataset:
    """A dataset folder: its manifest and a selection of its scenes.

    Iterating yields ``(SceneKey, Scene, FinalState)`` in horizon then index order.
    """

    root: Path
    manifest: DatasetManifest
    keys: tuple[SceneKey, ...]

    @property
    def dataset_hash(self) -> str:
        """The manifest's content hash (identifies the dataset in run records)."""
        return self.manifest.dataset_hash

    @property
    def horizons(self) -> list[float]:
        """Horizons present in the selection, ascending."""
        return sorted({k.horizon for k in self.keys})

    def select(self, horizons: Sequence[float] | None = None, limit: int | None = None) -> Dataset:
        """The scenes at ``horizons`` (all when ``None``), at most ``limit`` per horizon."""
        wanted = None if horizons is None else {float(h) for h in horizons}
        taken: dict[float, int] = {}
        keys = []
        for key in self.keys:
            if wanted is not None and key.horizon not in wanted:
                continue
            if limit is not None and taken.get(key.horizon, 0) >= limit:
                continue
            taken[key.horizon] = taken.get(key.horizon, 0) + 1
            keys.append(key)
        return Dataset(self.root, self.manifest, tuple(keys))

    def __len__(self) -> int:
        return len(self.keys)

    def __iter__(self) -> Iterator[tuple[SceneKey, Scene, FinalState]]:
        for key in self.keys:
            yield key, self.scene(key), self.final(key)

    def path(self, key: SceneKey, name: str) -> Path:
        """Path of file ``name`` (``init.png``) of scene ``key``."""
        return key.dir(self.root) / name

    def scene(self, key: SceneKey) -> Scene:
        """The scene's ``init.json``."""
        return read_model(self.path(key, INIT), Scene)

    def final(self, key: SceneKey) -> FinalState:
        """The scene's ``final.json`` (ground truth)."""
        return read_model(self.path(key, FINAL), FinalState)

    def verify(self) -> list[str]:
        """Files whose SHA-256 differs from ``checksums.sha256`` (or that are missing)."""
        path = self.root / CHECKSUMS
        try:
            lines = path.read_text(encoding="utf-8").splitlines()
        except OSError as exc:
            raise BadInput(f"{path}: cannot read: {exc.strerror or exc}") from None
        problems = []
        for line in lines:
            digest, _, rel = line.partition("  ")
            target = self.root / rel
            if not target.is_file():
                problems.append(f"{rel}: missing")
            elif hashlib.sha256(target.read_bytes()).hexdigest() != digest:
                problems.append(f"{rel}: content differs from its checksum")
        return problems


def load_dataset(
    root: str | Path, horizons: Sequence[float] | None = None, limit: int | None = None
) -> Dataset:
    """Open the dataset folder ``root`` (optionally narrowed with :meth:`Dataset.select`).

    Raises:
        BadInput: ``root`` is not a dataset or its manifest or index is corrupt.
    """
    root = Path(root)
    if not (root / MANIFEST).is_file():
        raise BadInput(f"{root}: not a bpb dataset (no {MANIFEST}); create one with bpb generate")
    manifest = read_model(root / MANIFEST, DatasetManifest)
    dataset = Dataset(root, manifest, tuple(_read_index(root / INDEX)))
    if horizons is None and limit is None:
        return dataset
    return dataset.select(horizons, limit)


def _read_index(path: Path) -> list[SceneKey]:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise BadInput(f"{path}: cannot read: {exc.strerror or exc}") from None
    reader = csv.DictReader(text.splitlines())
    missing = {"scene_id", "horizon", "index"} - set(reader.fieldnames or ())
    if missing:
        raise BadInput(f"{path}: header: missing column(s) {', '.join(sorted(missing))}")
    keys = []
    for line, row in enumerate(reader, start=2):
        try:
            key = SceneKey(float(row["horizon"]), int(row["index"]))
        except (TypeError, ValueError):
            raise BadInput(f"{path}: line {line}: bad horizon or index") from None
        if key.scene_id != row["scene_id"]:
            raise BadInput(f"{path}: line {line}: scene_id {row['scene_id']!r} != {key.scene_id}")
        keys.append(key)
    return sorted(keys)
