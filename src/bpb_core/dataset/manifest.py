"""The files that describe a dataset: ``dataset.json``, ``index.csv`` and ``checksums.sha256``,
and their writer (:class:`DatasetWriter`), which streams the index and the checksums to disk as
scenes arrive, then seals the manifest; only per-horizon counters (and whatever the scene
family's tallies keep) stay in memory.

The manifest holds no timestamps and no absolute paths, so two generations with the same seed,
config and software versions are byte-identical. ``dataset_hash`` is the SHA-256 of the
manifest's canonical JSON without that field; it changes whenever any file of the dataset does
(every file's hash is in ``checksums.sha256``, whose hash is in the manifest).
"""

from __future__ import annotations

import csv
import hashlib
import json
import platform
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from pydantic import BaseModel, ConfigDict, Field

from bpb_core.capabilities import HorizonTally
from bpb_core.errors import BadInput, blamed, writing
from bpb_core.layout import INDEX, MANIFEST, horizon_label
from bpb_core.plugin_calls import json_values, returned

if TYPE_CHECKING:
    from bpb_core.dataset.generate import SceneResult
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


def check_unedited(path: Path, fields: Mapping[str, Any] | None) -> None:
    """Refuse the ``dataset.json`` at ``path`` (its ``fields`` as read) when it was edited after
    ``bpb generate`` wrote it: its ``dataset_hash``, which runs record to identify the dataset,
    no longer matches its content, so two different datasets would look the same. The hash is
    recomputed from the file's own fields (:func:`content_hash`), so a manifest written by an
    earlier bpb still matches; one without a hash, or hand-made (no ``format``), is not checked.
    ``bpb run``, ``bpb human`` and ``bpb export`` all check it here.

    Raises:
        BadInput: One line naming ``dataset.json``.
    """
    if fields is None or "format" not in fields:
        return
    value = fields.get("dataset_hash")
    if isinstance(value, str) and value and content_hash(fields) != value:
        raise BadInput(
            f"{path}: edited after the dataset was generated: its dataset_hash "
            f"{value[:12]} no longer matches its content, and runs record that hash to "
            "identify the dataset; restore the file or generate the dataset again"
        )


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


VERSIONED = ("bpb", "pydantic", "pillow", "zlib-ng", "matplotlib", "numpy")


class DatasetWriter:
    """Appends index rows and checksums in scene order; writes the manifest.

    Attributes:
        tallies: The family's per-horizon tallies (empty when the family keeps none), whose
            ``add()`` and ``summary()`` are called checked: a failure names ``origin`` (who
            supplied the family) and ``family`` (how messages name it, ``scene family 'x'``).
    """

    def __init__(
        self,
        root: Path,
        horizons: Sequence[float],
        columns: Sequence[str],
        tallies: Mapping[float, HorizonTally] | None = None,
        origin: str = "",
        family: str = "",
    ) -> None:
        self.root = root
        self.counts = {h: HorizonSummary(scenes=0) for h in horizons}  # running counts
        self.tallies = dict(tallies or {})
        self.origin, self.family = origin, family
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
            with blamed(self.origin, f"{self._tally(row.horizon)} add()"):
                self.tallies[row.horizon].add(dict(row.values))
        # Checksums first: a Ctrl-C between the two leaves no index row whose files are unlisted
        with writing(self.root / CHECKSUMS):  # the buffer reaching the disk, which may be full
            self._sums.write("".join(f"{digest}  {rel}\n" for rel, digest in result.files))
        with writing(self.root / INDEX):
            self._rows.writerow(row.cells())

    def drop(self, horizon: float) -> None:
        """Count a scene dropped as unstable."""
        self.counts[horizon].dropped_unstable += 1

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
            extra = self._tally_summary(h) if h in self.tallies else {}
            out[horizon_label(h)] = HorizonSummary(**c.model_dump(), **extra)
        return out

    def _tally(self, horizon: float) -> str:
        return f"{self.family}: new_tally({horizon:g})'s"

    def _tally_summary(self, horizon: float) -> dict[str, Any]:
        """The tally's ``summary()``, checked: a dict that JSON can hold whose fields are not
        the counts bpb keeps itself (``scenes``)."""
        what = f"{self._tally(horizon)} summary()"
        with blamed(self.origin, what):
            summary = self.tallies[horizon].summary()
        fields = json_values(self.origin, what, summary, "what dataset.json")
        ours = sorted(set(fields) & set(HorizonSummary.model_fields))
        if ours:
            got = f"{ours[0]!r}, which bpb counts itself"
            raise returned(self.origin, what, got, "the family's own fields")
        return fields

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
