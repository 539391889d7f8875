"""Streams a dataset's descriptive files to disk while scenes arrive, then seals the manifest.

``index.csv`` and ``checksums.sha256`` are appended scene by scene; only per-horizon counters (and
whatever the scene family's tallies keep) stay in memory.
"""

from __future__ import annotations

import csv
import platform
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import IO, Any

from bpb_core.capabilities import HorizonTally
from bpb_core.dataset.manifest import (
    CHECKSUMS,
    DatasetManifest,
    HorizonSummary,
    IndexRow,
    sha256_bytes,
)
from bpb_core.dataset.worker import SceneResult
from bpb_core.errors import writing
from bpb_core.layout import INDEX, MANIFEST, horizon_label

VERSIONED = ("bpb", "pydantic", "pillow", "zlib-ng", "matplotlib", "numpy")


@dataclass
class HorizonCounts:
    """Running counts of one horizon that every family has."""

    scenes: int = 0
    unstable: int = 0
    dropped: int = 0


class DatasetWriter:
    """Appends index rows and checksums in scene order; writes the manifest.

    Attributes:
        tallies: The family's per-horizon tallies (empty when the family keeps none).
    """

    def __init__(
        self,
        root: Path,
        horizons: Sequence[float],
        columns: Sequence[str],
        tallies: Mapping[float, HorizonTally] | None = None,
    ) -> None:
        self.root = root
        self.counts = {h: HorizonCounts() for h in horizons}
        self.tallies = dict(tallies or {})
        with writing(root):
            self._index: IO[str] = (root / INDEX).open("w", encoding="utf-8", newline="")
            self._sums: IO[str] = (root / CHECKSUMS).open("w", encoding="utf-8", newline="")
        self._rows = csv.writer(self._index, lineterminator="\n")
        with writing(root / INDEX):
            self._rows.writerow(IndexRow.header(columns))

    def add(self, result: SceneResult) -> None:
        """Record a kept scene."""
        row = result.row
        counts = self.counts[row.horizon]
        counts.scenes += 1
        counts.unstable += row.stable is False
        if row.horizon in self.tallies:
            self.tallies[row.horizon].add(dict(row.values))
        # Checksums first: a Ctrl-C between the two leaves no index row whose files are unlisted
        with writing(self.root / CHECKSUMS):  # the buffer reaching the disk, which may be full
            self._sums.write("".join(f"{digest}  {rel}\n" for rel, digest in result.files))
        with writing(self.root / INDEX):
            self._rows.writerow(row.cells())

    def drop(self, horizon: float) -> None:
        """Count a scene dropped as unstable."""
        self.counts[horizon].dropped += 1

    def add_file(self, rel: str) -> None:
        """Checksum an extra file (a stats figure) written under the root."""
        digest = sha256_bytes((self.root / rel).read_bytes())
        with writing(self.root / CHECKSUMS):
            self._sums.write(f"{digest}  {rel}\n")

    def close(self) -> None:
        """Flush and close the streamed files (both, even when the first cannot be)."""
        try:
            with writing(self.root / INDEX):
                self._index.close()
        finally:
            with writing(self.root / CHECKSUMS):
                self._sums.close()

    def summary(self) -> dict[str, HorizonSummary]:
        """Per-horizon counts (with the family's fields) keyed by horizon label (``h3``)."""
        out = {}
        for h, c in self.counts.items():
            extra: dict[str, Any] = self.tallies[h].summary() if h in self.tallies else {}
            out[horizon_label(h)] = HorizonSummary(
                scenes=c.scenes, dropped_unstable=c.dropped, unstable=c.unstable, **extra
            )
        return out

    def write_manifest(self, manifest: DatasetManifest) -> DatasetManifest:
        """Add the descriptive files' hashes, seal and write ``dataset.json``."""
        files = {name: sha256_bytes((self.root / name).read_bytes()) for name in (INDEX, CHECKSUMS)}
        sealed = manifest.model_copy(update={"files": files}).sealed()
        with writing(self.root / MANIFEST):
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
