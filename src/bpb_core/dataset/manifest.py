"""The files that describe a dataset: ``dataset.json``, ``index.csv`` and ``checksums.sha256``.

The manifest holds no timestamps and no absolute paths, so two generations with the same seed,
config and software versions are byte-identical. ``dataset_hash`` is the SHA-256 of the
manifest's canonical JSON without that field; it changes whenever any file of the dataset does
(every file's hash is in ``checksums.sha256``, whose hash is in the manifest).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
from dataclasses import astuple, dataclass, fields
from typing import Any

from pydantic import BaseModel, ConfigDict, Field

FORMAT = "bpb-dataset/1"
CHECKSUMS = "checksums.sha256"


class HorizonSummary(BaseModel):
    """Counts of one horizon.

    Attributes:
        scenes: Scenes kept.
        cue_collisions: Scenes whose cue ball touches another ball by the horizon.
        collision_rate: ``cue_collisions / scenes``.
        dropped_unstable: Scenes drawn but dropped by ``--stable-only``.
        unstable: Kept scenes whose stability annotation says unstable.
        speed_range: The cue-speed range used, ``[low, high]`` in m/s.
    """

    model_config = ConfigDict(extra="forbid")

    scenes: int
    cue_collisions: int
    collision_rate: float
    dropped_unstable: int = 0
    unstable: int = 0
    speed_range: tuple[float, float]


class DatasetManifest(BaseModel):
    """The content of ``dataset.json``."""

    model_config = ConfigDict(extra="allow")

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

    def to_json(self) -> str:
        """Canonical JSON text (sorted keys, fixed indentation, trailing newline)."""
        return json.dumps(self.model_dump(mode="json"), indent=2, sort_keys=True) + "\n"

    def sealed(self) -> DatasetManifest:
        """A copy with ``dataset_hash`` computed from everything else."""
        body = self.model_copy(update={"dataset_hash": ""}).to_json()
        return self.model_copy(update={"dataset_hash": hashlib.sha256(body.encode()).hexdigest()})


@dataclass(frozen=True)
class IndexRow:
    """One line of ``index.csv``: a scene and what happens in it."""

    scene_id: str
    horizon: float
    index: int
    cue_speed: float
    cue_angle_deg: float
    cue_collision: bool
    cue_contacts: str
    cue_walls: str
    pocketed: str
    events: int
    stable: bool | None

    @classmethod
    def header(cls) -> list[str]:
        """Column names, in order."""
        return [f.name for f in fields(cls)]

    def cells(self) -> list[str]:
        """The row as CSV cells (booleans as ``true``/``false``, empty when unknown)."""
        out: list[str] = []
        for value in astuple(self):
            if isinstance(value, bool):
                out.append("true" if value else "false")
            elif value is None:
                out.append("")
            elif isinstance(value, float):
                out.append(f"{value:.6g}" if value == int(value) else f"{value:.6f}")
            else:
                out.append(str(value))
        return out


def csv_line(cells: list[str]) -> str:
    """One CSV line with ``\\n`` line ending."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(cells)
    return buf.getvalue()


def sha256_bytes(data: bytes) -> str:
    """Hex SHA-256 of ``data``."""
    return hashlib.sha256(data).hexdigest()
