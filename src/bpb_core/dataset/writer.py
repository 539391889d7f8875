"""Streams a dataset's descriptive files to disk while scenes arrive, then seals the manifest.

``index.csv`` and ``checksums.sha256`` are appended scene by scene; only per-horizon counters and
cue speeds (one float per scene, for the histogram) stay in memory.
"""

from __future__ import annotations

import platform
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import IO, Any

from bpb_core.dataset.manifest import (
    CHECKSUMS,
    DatasetManifest,
    HorizonSummary,
    IndexRow,
    csv_line,
    sha256_bytes,
)
from bpb_core.dataset.worker import SceneResult
from bpb_core.layout import INDEX, MANIFEST, horizon_label

VERSIONED = ("bpb", "pydantic", "pillow", "matplotlib", "numpy")


@dataclass
class HorizonTally:
    """Running counts of one horizon."""

    scenes: int = 0
    collisions: int = 0
    unstable: int = 0
    dropped: int = 0
    speeds: list[float] = field(default_factory=list)


class DatasetWriter:
    """Appends index rows and checksums in scene order; writes the stats and the manifest."""

    def __init__(self, root: Path, horizons: Sequence[float]) -> None:
        self.root = root
        self.tallies = {h: HorizonTally() for h in horizons}
        self._index: IO[str] = (root / INDEX).open("w", encoding="utf-8", newline="")
        self._sums: IO[str] = (root / CHECKSUMS).open("w", encoding="utf-8", newline="")
        self._index.write(csv_line(IndexRow.header()))

    def add(self, result: SceneResult) -> None:
        """Record a kept scene."""
        row = result.row
        tally = self.tallies[row.horizon]
        tally.scenes += 1
        tally.collisions += row.cue_collision
        tally.unstable += row.stable is False
        tally.speeds.append(row.cue_speed)
        self._index.write(csv_line(row.cells()))
        for rel, digest in result.files:
            self._sums.write(f"{digest}  {rel}\n")

    def drop(self, horizon: float) -> None:
        """Count a scene dropped as unstable."""
        self.tallies[horizon].dropped += 1

    def add_file(self, rel: str) -> None:
        """Checksum an extra file (a stats figure) written under the root."""
        self._sums.write(f"{sha256_bytes((self.root / rel).read_bytes())}  {rel}\n")

    def close(self) -> None:
        """Flush and close the streamed files."""
        self._index.close()
        self._sums.close()

    def summary(self, speed_ranges: dict[float, tuple[float, float]]) -> dict[str, HorizonSummary]:
        """Per-horizon counts keyed by horizon label (``h3``)."""
        out = {}
        for h, t in self.tallies.items():
            out[horizon_label(h)] = HorizonSummary(
                scenes=t.scenes,
                cue_collisions=t.collisions,
                collision_rate=round(t.collisions / t.scenes, 6) if t.scenes else 0.0,
                dropped_unstable=t.dropped,
                unstable=t.unstable,
                speed_range=speed_ranges[h],
            )
        return out

    def write_manifest(self, manifest: DatasetManifest) -> DatasetManifest:
        """Add the descriptive files' hashes, seal and write ``dataset.json``."""
        files = {name: sha256_bytes((self.root / name).read_bytes()) for name in (INDEX, CHECKSUMS)}
        sealed = manifest.model_copy(update={"files": files}).sealed()
        (self.root / MANIFEST).write_text(sealed.to_json(), encoding="utf-8")
        return sealed


def versions() -> dict[str, str]:
    """Versions of Python and of the packages whose output lands in the dataset."""
    found = {"python": platform.python_version()}
    for name in VERSIONED:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return found


def plugin_label(registered: Any) -> str:
    """``name (distribution version)`` of a registered component."""
    return f"{registered.info.name} ({registered.distribution} {registered.version})"
