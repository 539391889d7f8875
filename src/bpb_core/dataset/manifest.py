"""The files that describe a dataset: ``dataset.json``, ``index.csv`` and ``checksums.sha256``.

The manifest holds no timestamps and no absolute paths, so two generations with the same seed,
config and software versions are byte-identical. ``dataset_hash`` is the SHA-256 of the
manifest's canonical JSON without that field; it changes whenever any file of the dataset does
(every file's hash is in ``checksums.sha256``, whose hash is in the manifest).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel, ConfigDict, Field

from bpb_core.errors import BadInput

if TYPE_CHECKING:
    from bpb_core.registry import Registry

FORMAT = "bpb-dataset/1"
CHECKSUMS = "checksums.sha256"


def check_simulator(manifest: Path, name: str, registry: Registry, hint: str = "") -> None:
    """Refuse a simulator ``name`` that the dataset's ``manifest`` config names but that is not
    installed (a dataset made with a simulator plugin since uninstalled).

    Raises:
        BadInput: One line naming the manifest, its config, the simulator and the installed
            ones, then ``hint``.
    """
    known = registry.names("simulator")
    if name not in known:
        raise BadInput(
            f"{manifest}: config: names simulator {name!r}, which is not installed "
            f"(installed: {', '.join(known) or 'none'}){hint}"
        )


class HorizonSummary(BaseModel):
    """Counts of one horizon; the scene family adds its own fields (``extra``).

    Attributes:
        scenes: Scenes kept.
        dropped_unstable: Scenes drawn but dropped by ``--stable-only``.
        unstable: Kept scenes whose stability annotation says unstable.
    """

    model_config = ConfigDict(extra="allow", strict=True)

    scenes: int
    dropped_unstable: int = 0
    unstable: int = 0


class DatasetManifest(BaseModel):
    """The content of ``dataset.json``."""

    model_config = ConfigDict(extra="allow", strict=True)  # "4" is no count, "yes" no flag

    format: str = FORMAT
    dataset_hash: str = ""
    seed: int
    per_horizon: int
    horizons: list[float]
    stable_only: bool = False
    images: bool = True
    scenes: int
    summary: dict[str, HorizonSummary]
    config: dict[str, Any]
    physics: dict[str, Any] = Field(default_factory=dict)
    calibration: dict[str, Any] | None = None
    plugins: dict[str, str] = Field(default_factory=dict)
    versions: dict[str, str] = Field(default_factory=dict)
    files: dict[str, str] = Field(default_factory=dict)

    @property
    def family(self) -> str | None:
        """The scene family that made the dataset (the config's ``family``)."""
        name = self.config.get("family")
        return name if isinstance(name, str) and name else None

    def to_json(self) -> str:
        """Canonical JSON text (sorted keys, fixed indentation, trailing newline)."""
        return json.dumps(self.model_dump(mode="json"), indent=2, sort_keys=True) + "\n"

    def sealed(self) -> DatasetManifest:
        """A copy with ``dataset_hash`` computed from everything else."""
        digest = content_hash(self.model_dump(mode="json"))
        return self.model_copy(update={"dataset_hash": digest})


def content_hash(fields: Mapping[str, Any]) -> str:
    """The ``dataset_hash`` of a manifest holding ``fields``: the SHA-256 of its canonical JSON
    (as :meth:`DatasetManifest.to_json` writes it) with ``dataset_hash`` empty. Given the fields
    of a ``dataset.json`` as read, it gives the hash the bpb that wrote the file recorded, even
    one whose manifest lacked fields added since (``physics``)."""
    body = json.dumps({**fields, "dataset_hash": ""}, indent=2, sort_keys=True) + "\n"
    return hashlib.sha256(body.encode()).hexdigest()


@dataclass(frozen=True)
class IndexRow:
    """One line of ``index.csv``: a scene, the family's cells about it, and its stability.

    Attributes:
        values: The family's cells, in the order of its ``index_columns``.
        stable: The stability annotation's verdict (``None``: not annotated).
    """

    scene_id: str
    horizon: float
    index: int
    values: tuple[tuple[str, object], ...]
    stable: bool | None

    @staticmethod
    def header(columns: Sequence[str]) -> list[str]:
        """Column names, in order, for a family with ``columns``."""
        return ["scene_id", "horizon", "index", *columns, "stable"]

    def get(self, column: str) -> object:
        """The family's cell ``column``."""
        return dict(self.values)[column]

    def cells(self) -> list[str]:
        """The row as CSV cells (booleans as ``true``/``false``, empty when unknown)."""
        values = [self.scene_id, self.horizon, self.index, *(v for _, v in self.values)]
        return [cell(v) for v in [*values, self.stable]]


def cell(value: object) -> str:
    """One CSV cell: ``true``/``false``, empty for ``None``, 6 decimals for fractional floats."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.6g}" if value == int(value) else f"{value:.6f}"
    return str(value)


def sha256_bytes(data: bytes) -> str:
    """Hex SHA-256 of ``data``."""
    return hashlib.sha256(data).hexdigest()
