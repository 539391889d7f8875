"""The scenes a run asks about, read lazily from a dataset folder.

Only ``init.json`` (and ``init.png`` for image input) is read: the runner never looks at ground
truth. Scenes stream one at a time so a large dataset costs no memory up front.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from bpb_core.errors import BadInput
from bpb_core.layout import INIT, MANIFEST, SceneKey, iter_scene_keys
from bpb_core.model_files import read_model
from bpb_core.scene import Scene

IMAGE = "init.png"


@dataclass(frozen=True)
class SceneRef:
    """A scene of the dataset, not yet loaded."""

    key: SceneKey
    folder: Path

    @property
    def scene_id(self) -> str:
        return self.key.scene_id

    def load(self) -> Scene:
        """Read and validate ``init.json``.

        Raises:
            BadInput: The file is missing or invalid (names the file and the field).
        """
        return read_model(self.folder / INIT, Scene)

    def image(self) -> bytes:
        """The bytes of ``init.png``.

        Raises:
            BadInput: The image is missing (image input modes need it).
        """
        path = self.folder / IMAGE
        try:
            return path.read_bytes()
        except OSError:
            raise BadInput(f"{path}: missing; use --input-mode state for text-only runs") from None


def select_scenes(
    data: Path, horizons: Sequence[float] | None = None, limit: int | None = None
) -> list[SceneRef]:
    """Scenes of ``data`` at ``horizons`` (all when ``None``), the first ``limit`` per horizon.

    Raises:
        BadInput: ``data`` is not a dataset folder or no scene matches.
    """
    if not data.is_dir():
        raise BadInput(f"{data}: --data: not a dataset folder")
    wanted = None if horizons is None else {float(h) for h in horizons}
    taken: dict[float, int] = {}
    refs: list[SceneRef] = []
    for key in iter_scene_keys(data):
        if wanted is not None and key.horizon not in wanted:
            continue
        if limit is not None and taken.get(key.horizon, 0) >= limit:
            continue
        taken[key.horizon] = taken.get(key.horizon, 0) + 1
        refs.append(SceneRef(key, key.dir(data)))
    if not refs:
        raise BadInput(f"{data}: --data: no scenes (h*/scene_*/init.json) match the selection")
    return refs


def dataset_hash(data: Path) -> str:
    """A hash identifying the dataset: the manifest's own when it records one, else a digest of
    ``dataset.json`` (or, without a manifest, of every ``init.json``)."""
    manifest = data / MANIFEST
    if manifest.exists():
        try:
            import json

            recorded = json.loads(manifest.read_text(encoding="utf-8")).get("dataset_hash")
        except (OSError, ValueError, AttributeError):
            recorded = None
        if isinstance(recorded, str) and recorded:
            return recorded
        return hashlib.sha256(manifest.read_bytes()).hexdigest()
    digest = hashlib.sha256()
    for key in iter_scene_keys(data):
        path = key.dir(data) / INIT
        if path.exists():
            digest.update(path.read_bytes())
    return digest.hexdigest()
