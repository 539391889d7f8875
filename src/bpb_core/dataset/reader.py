"""Read a generated dataset: manifest, scene list and the scenes with their ground truth; and
the check that a scene file read for use is the file that was generated.

Scenes are read lazily, one folder at a time, with the models of the scene family that made the
dataset. Every corrupt or missing file raises :class:`~bpb_core.errors.BadInput` naming the file
(and the field, for JSON files). :class:`DatasetScene` is what iterating or indexing a
:class:`Dataset` yields: it reads ``init.json`` and ``final.json`` on first use and names every
image file of the scene, so embedding code never spells a file name itself.

``bpb run``, ``bpb report``, ``bpb export`` and the library read a scene's files through
:func:`read_scene_file` (JSON through :func:`read_scene_model`), so a file changed after
generation (an edited ``final.json`` would silently change every score) is refused in one line
naming it, instead of being used. Folders without ``checksums.sha256`` (hand-made scenes) and
files it does not list are read unchecked; a ``checksums.sha256`` that cannot be read or holds a
line that is no checksum is refused naming it (else it would turn the check off).
:meth:`Dataset.verify` lists every difference at once.

A Hugging Face export of a dataset (``bpb export --format hf``,
:mod:`bpb_core.library.hf_export`: Parquet shards under ``data/``, the manifest, index and
checksums verbatim under ``bpb/``) is read as the dataset folder it came from:
:func:`resolve_data` unpacks each scene's ``init.json``, ``final.json`` and input image, byte for
byte, into a cache folder named by the export's content (``hf/<digest>`` of :func:`cache_root`),
once.
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import re
import shutil
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING, Any, TypeVar

from pydantic import BaseModel

from bpb_core.dataset.manifest import CHECKSUMS, DatasetManifest, content_hash
from bpb_core.errors import BadInput, UnknownScene, need_module
from bpb_core.interfaces import SceneFamily
from bpb_core.layout import FINAL, INDEX, INIT, MANIFEST, SceneKey, iter_scene_keys, select_keys
from bpb_core.model_calls import non_finite
from bpb_core.plugin_calls import loaded_config, simulator_named
from bpb_core.scored_units import object_origin
from bpb_core.simulator_spec import SimulatorSpec, parse_spec
from bpb_core.validated_files import read_bytes, read_model, validate_mapping

if TYPE_CHECKING:
    from bpb_core.interfaces import SceneFamily
    from bpb_core.registry import Registry


DATA = "data"
SIDE = "bpb"
_SHARD_COLUMNS = ["horizon", "index", "image", "scene", "truth"]


def shard_name(split: str, number: int, count: int) -> str:
    """``data/h3-00000-of-00002.parquet``: the file pattern ``datasets`` reads splits from."""
    return f"{DATA}/{split}-{number:05d}-of-{count:05d}.parquet"


def is_hf_export(path: Path) -> bool:
    """Whether ``path`` is a folder written by ``bpb export --format hf``."""
    return (path / SIDE / MANIFEST).is_file() and (path / DATA).is_dir()


def resolve_data(data: str | Path) -> Path:
    """``data`` itself for a dataset folder; for a Hugging Face export, the folder it unpacks to.

    Raises:
        BadInput: The export is incomplete or a shard cannot be read (names the file).
    """
    path = Path(data)
    if (path / MANIFEST).exists() or not is_hf_export(path):
        return path
    shards = sorted((path / DATA).glob("*.parquet"))
    if not shards:
        raise BadInput(f"{path / DATA}: no Parquet shards; export the dataset again")
    target = cache_root() / "hf" / _digest(path, shards)
    if not (target / MANIFEST).is_file():
        _unpack(path, shards, target)
    return target


def cache_root() -> Path:
    """``$BPB_CACHE_DIR``, else ``$XDG_CACHE_HOME/bpb``, else ``~/.cache/bpb``."""
    if os.environ.get("BPB_CACHE_DIR"):
        return Path(os.environ["BPB_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "bpb"


def _digest(path: Path, shards: list[Path]) -> str:
    digest = hashlib.sha256()
    # checksums only when there (an export made before they were kept keeps its digest)
    sums = [path / SIDE / CHECKSUMS] if (path / SIDE / CHECKSUMS).is_file() else []
    for file in [path / SIDE / MANIFEST, path / SIDE / INDEX, *sums, *shards]:
        digest.update(file.name.encode() + b"\0")
        digest.update(read_bytes(file))
    return digest.hexdigest()[:24]


def _unpack(path: Path, shards: list[Path], target: Path) -> None:
    """Write the scenes to a fresh folder beside ``target``, then move it into place, so an
    interrupted unpack leaves no half folder behind under the final name."""
    partial = target.with_name(f"{target.name}.partial-{os.getpid()}")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    try:
        for shard in shards:
            _unpack_shard(shard, partial)
        shutil.copyfile(path / SIDE / INDEX, partial / INDEX)
        shutil.copyfile(path / SIDE / MANIFEST, partial / MANIFEST)
        if (path / SIDE / CHECKSUMS).is_file():
            shutil.copyfile(path / SIDE / CHECKSUMS, partial / CHECKSUMS)
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    try:
        partial.rename(target)
    except OSError:  # another process unpacked the same export first
        shutil.rmtree(partial, ignore_errors=True)


def _unpack_shard(shard: Path, out: Path) -> None:
    pq = need_module("pyarrow.parquet", "reading a Hugging Face export", "pip install 'bpb[hf]'")

    try:
        table = pq.read_table(shard, columns=_SHARD_COLUMNS)
    except Exception as exc:  # pyarrow raises several types for a bad file
        raise BadInput(f"{shard}: not a bpb export shard: {exc}") from None
    for number, row in enumerate(table.to_pylist()):
        if not isinstance(row["scene"], str) or not isinstance(row["truth"], str):
            raise BadInput(f"{shard}: row {number}: scene and truth must be JSON text")
        horizon, index = row["horizon"], row["index"]
        if not (
            isinstance(horizon, int | float) and math.isfinite(horizon) and horizon > 0
        ) or not (isinstance(index, int) and index >= 0):
            raise BadInput(
                f"{shard}: row {number}: horizon and index must be a positive number of seconds "
                f"and a scene number, not {horizon!r} and {index!r}"
            )
        folder = SceneKey(float(horizon), index).dir(out)
        if (folder / INIT).exists():
            continue  # one row per task: the scene's files are written once
        folder.mkdir(parents=True, exist_ok=True)
        (folder / INIT).write_bytes(row["scene"].encode("utf-8"))
        (folder / FINAL).write_bytes(row["truth"].encode("utf-8"))
        image = row["image"]
        if image is not None and image.get("bytes"):
            # only the file name: an image never lands outside its scene's folder
            name = Path(str(image.get("path") or "")).name
            if name in ("", ".", "..") or name in (INIT, FINAL):
                raise BadInput(
                    f"{shard}: row {number}: image.path: {image.get('path')!r} is not an "
                    "image file name"
                )
            (folder / name).write_bytes(image["bytes"])


M = TypeVar("M", bound=BaseModel)
_SHA256 = re.compile(r"[0-9a-f]{64}")


def parse_line(line: str) -> tuple[str, str] | None:
    """``(sha256, path)`` of a ``checksums.sha256`` line, or ``None`` when it is not
    ``<sha256>  <path inside the dataset>``."""
    digest, _, rel = line.partition("  ")
    if _SHA256.fullmatch(digest) and inside(rel):
        return digest, rel
    return None


def inside(rel: str) -> bool:
    """Whether ``rel`` names a file inside the dataset (relative, no ``..``, not empty)."""
    path = PurePosixPath(rel)
    return bool(rel) and not path.is_absolute() and ".." not in path.parts and "\\" not in rel


def read_scene_file(path: Path) -> bytes:
    """The bytes of a scene's file (``DIR/h{t}/scene_{i}/NAME``), checked against the dataset's
    ``checksums.sha256`` (:func:`check_recorded`).

    Raises:
        BadInput: The file cannot be read, or differs from its recorded checksum.
    """
    data = read_bytes(path)
    check_recorded(path, data)
    return data


def read_scene_model(path: Path, model: type[M]) -> M:
    """A scene's JSON file read with ``model``; a file that does not validate is named with its
    field first, then one that validates but was changed after generation."""
    data = read_bytes(path)
    value = read_model(path, model, data)
    check_recorded(path, data)
    return value


def check_recorded(path: Path, data: bytes) -> None:
    """Refuse ``data`` (read from the scene file ``path``) when the dataset's
    ``checksums.sha256`` records another hash for it.

    Raises:
        BadInput: The hashes differ (names the file and what to do), or
            ``checksums.sha256`` cannot be read or holds a line that is no checksum (names it).
    """
    root = path.parent.parent.parent
    recorded = _recorded(root)
    if not recorded:
        return
    rel = f"{path.parent.parent.name}/{path.parent.name}/{path.name}"
    digest = recorded.get(rel)
    if digest is not None and hashlib.sha256(data).hexdigest() != digest:
        raise BadInput(
            f"{path}: changed after the dataset was generated (its hash differs from "
            f"{root / CHECKSUMS}); scores would not be the dataset's: regenerate the dataset, "
            f"or remove {CHECKSUMS} to use edited files unchecked"
        )


def _recorded(root: Path) -> dict[str, str]:
    """The hashes ``root/checksums.sha256`` records by path (empty without the file); read
    again when the file changes."""
    identity = _identity(root / CHECKSUMS)
    return {} if identity is None else _parse_file(root / CHECKSUMS, identity)


_UNCHECKED = f"regenerate the dataset, or remove {CHECKSUMS} to use its files unchecked"


@lru_cache(maxsize=16)
def _parse_file(path: Path, identity: tuple[int, int, int]) -> dict[str, str]:
    """The hashes of ``path`` by scene file; a file that cannot be read, or a line that is no
    checksum, is refused: skipped, it would turn the check off for the files it should list."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, ValueError) as exc:
        why = getattr(exc, "strerror", None) or exc
        raise BadInput(f"{path}: cannot read: {why}; {_UNCHECKED}") from None
    recorded: dict[str, str] = {}
    for number, line in enumerate(lines, 1):
        entry = parse_line(line)
        if entry is None:
            raise BadInput(
                f"{path}: line {number}: not '<sha256>  <path inside the dataset>', so the "
                f"scene files cannot be checked against it; {_UNCHECKED}"
            )
        recorded[entry[1]] = entry[0]
    if not recorded:
        raise BadInput(f"{path}: records no checksum; {_UNCHECKED}")
    return recorded


INPUT = "input"
"""The image kind models see (the family's ``input_image``)."""


@dataclass(frozen=True)
class DatasetScene:
    """A scene of a dataset folder.

    Attributes:
        key: Horizon and index.
        folder: The scene's folder (``DIR/h{t}/scene_{i:04d}``).
        family: The scene family that made it.
    """

    key: SceneKey
    folder: Path
    family: SceneFamily

    @property
    def scene_id(self) -> str:
        """The scene's id (``h3_0007``)."""
        return self.key.scene_id

    @property
    def horizon(self) -> float:
        """Seconds the questions are about."""
        return self.key.horizon

    @cached_property
    def state(self) -> Any:
        """The initial state: ``init.json`` read with the family's scene model."""
        return read_scene_model(self.folder / INIT, self.family.scene_model)

    @cached_property
    def truth(self) -> Any:
        """The ground truth: ``final.json`` read with the family's truth model."""
        return read_scene_model(self.folder / FINAL, self.family.truth_model)

    @property
    def stable(self) -> bool | None:
        """The truth's stability flag (``None`` when not annotated)."""
        stable: bool | None = self.truth.stable
        return stable

    @property
    def image_kinds(self) -> tuple[str, ...]:
        """The kinds :meth:`image_path` accepts: ``input`` and each image's stem."""
        return (INPUT, *(Path(name).stem for name in self.family.image_names))

    def image_path(self, kind: str = INPUT) -> Path:
        """Path of one of the scene's images.

        Args:
            kind: ``input`` (the image models are shown) or the stem of one of the family's
                images (``init``, ``final``, ...); a full file name works too.

        Raises:
            BadInput: The family has no such image (names the kinds it has).
        """
        name = self.family.input_image if kind == INPUT else None
        for image in self.family.image_names:
            if kind in (image, Path(image).stem):
                name = image
        if name is None:
            kinds = ", ".join(self.image_kinds)
            raise BadInput(f"{self.scene_id}: image kind {kind!r}: the scene has {kinds}")
        return self.folder / name

    def image_bytes(self, kind: str = INPUT) -> bytes:
        """The bytes of :meth:`image_path`, checked to be a whole image (:func:`check_image`)
        and the generated one (:func:`check_recorded`).

        Raises:
            BadInput: No such kind, or the file is missing, truncated, damaged or changed.
        """
        path = self.image_path(kind)
        data = read_bytes(path)
        check_image(path, data)
        check_recorded(path, data)
        return data


def check_image(path: Path, data: bytes) -> None:
    """Refuse an image Pillow cannot read whole (a truncated or damaged file), or of another
    format than its name says (a JPEG saved as ``init.png`` goes out labelled as a PNG), which
    would otherwise be sent to a model (and paid for), exported, printed or shown as it is.
    Every reader of a scene's image goes through here. ``verify`` walks the file's structure
    and checksums without decoding the pixels.

    Raises:
        BadInput: ``data`` (read from ``path``) is not a readable image (names ``path``).
    """
    import io

    from PIL import Image, UnidentifiedImageError

    why = None
    try:
        with Image.open(io.BytesIO(data)) as image:
            found = image.format
            image.verify()
        # the extensions Image.open registered (PNG, JPEG, GIF, BMP, ...); registered_extensions()
        # would import every Pillow plugin first
        named = Image.EXTENSION.get(path.suffix.lower())
        if named is not None and found != named:
            why = f"a {found} image, but its name says {named}"
    except UnidentifiedImageError:  # its message shows a BytesIO object, not the file
        why = "an empty file" if not data else "not an image file Pillow can read"
    except Exception as exc:  # Pillow raises several types for a damaged file
        why = f"{type(exc).__name__}: {exc}"
    if why is not None:
        raise BadInput(
            f"{path}: not a readable image ({why}); the dataset is damaged: "
            "load_dataset(...).verify() lists what changed"
        )


def read_scene_files(folder: Path, scene_model: Any, truth_model: Any) -> tuple[Any, Any]:
    """The scene (``init.json``) and ground truth (``final.json``) of the scene ``folder``,
    read with the family's models, uncached: ``bpb run`` checks them this way before its first
    call, so a damaged ``final.json`` stops a run before it costs anything.

    Raises:
        BadInput: A file is missing or invalid (names the file and the field), or changed after
            generation (:mod:`bpb_core.dataset.reader`).
    """
    return read_scene_model(folder / INIT, scene_model), read_scene_model(
        folder / FINAL, truth_model
    )


def read_truth(dataset: Path, key: SceneKey, scene_model: Any, truth_model: Any) -> tuple[Any, Any]:
    """:func:`read_scene_files` of scene ``key`` of ``dataset``, cached for scoring. The cache
    is keyed on both files' identity (modification time, size, inode), so a long-lived process
    (``bpb view``, a notebook) reads a scene again once its files change, and gets the new
    content or the checksum refusal, never the ground truth it read before.

    Raises:
        BadInput: A file is missing or invalid (names the file and the field), or changed after
            generation.
    """
    folder = key.dir(dataset)
    identity = (_identity(folder / INIT), _identity(folder / FINAL))
    return _read_truth(folder, scene_model, truth_model, identity)


def _identity(path: Path) -> tuple[int, int, int] | None:
    """``(st_mtime_ns, st_size, st_ino)`` of ``path`` (``None``: it cannot be read, and the
    read names why)."""
    try:
        stat = path.stat()
    except OSError:
        return None
    return stat.st_mtime_ns, stat.st_size, stat.st_ino


@lru_cache(maxsize=65536)
def _read_truth(
    folder: Path, scene_model: Any, truth_model: Any, identity: tuple[object, object]
) -> tuple[Any, Any]:
    return read_scene_files(folder, scene_model, truth_model)


@dataclass(frozen=True)
class Dataset:
    """A dataset folder: its manifest, its scene family and a selection of its scenes.

    Iterating yields a :class:`~bpb_core.dataset.reader.DatasetScene` per scene in horizon
    then index order; ``dataset["h3_0007"]`` looks one up by its id. Each reads its
    ``init.json`` (``.state``) and ``final.json`` (``.truth``) with the family's models on use.

    Attributes:
        export: The Hugging Face export ``root`` was unpacked from (``None``: a dataset folder).
    """

    root: Path
    manifest: DatasetManifest
    keys: tuple[SceneKey, ...]
    family: SceneFamily
    export: Path | None = None

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
        keys = select_keys(self.keys, horizons, limit)
        return Dataset(self.root, self.manifest, tuple(keys), self.family, self.export)

    def __len__(self) -> int:
        return len(self.keys)

    def __iter__(self) -> Iterator[DatasetScene]:
        for key in self.keys:
            yield DatasetScene(key, key.dir(self.root), self.family)

    def __getitem__(self, scene_id: str) -> DatasetScene:
        """The scene with id ``scene_id`` (``h3_0007``).

        Raises:
            UnknownScene: A ``KeyError`` (and a ``BadInput``): no scene of the selection has
                that id; names the folder and the id and says how to list ids.
        """
        for key in self.keys:
            if key.scene_id == scene_id:
                return DatasetScene(key, key.dir(self.root), self.family)
        raise UnknownScene(self.root, scene_id, self.keys[0].scene_id if self.keys else None)

    def __contains__(self, scene_id: object) -> bool:
        return any(key.scene_id == scene_id for key in self.keys)

    def path(self, key: SceneKey, name: str) -> Path:
        """Path of file ``name`` (``init.png``) of scene ``key``."""
        return key.dir(self.root) / name

    def scene(self, key: SceneKey) -> Any:
        """The scene's ``init.json``, read with the family's scene model."""
        return read_scene_model(self.path(key, INIT), self.family.scene_model)

    def truth(self, key: SceneKey) -> Any:
        """The scene's ``final.json`` (ground truth), read with the family's truth model."""
        return read_scene_model(self.path(key, FINAL), self.family.truth_model)

    def verify(self) -> list[str]:
        """What differs from the dataset as it was generated: files whose SHA-256 differs from
        ``checksums.sha256`` (or that are missing); ``index.csv`` or ``checksums.sha256`` unlike
        the hashes the manifest records; a manifest whose ``dataset_hash`` does not match its
        content; scene folders ``index.csv`` does not list, or listed scenes without a folder.
        An empty list means the dataset is intact.

        For a Hugging Face export the same, but only the files an export carries are checked
        against ``checksums.sha256`` (each scene's ``init.json``, ``final.json`` and input
        image; not the other images or the stats figures).

        Raises:
            BadInput: ``checksums.sha256`` cannot be read, or the export has none (an export
                made by an earlier bpb).
        """
        carried: set[str] | None = None  # the names of the scene files an export carries
        if self.export is not None:
            if not (self.root / CHECKSUMS).is_file():
                raise BadInput(
                    f"{self.export}: this Hugging Face export has no {SIDE}/{CHECKSUMS} (made by "
                    "an earlier bpb), so its scene files cannot be checked: export the dataset "
                    "again, or verify the dataset folder it came from"
                )
            image = self.family.input_image if self.manifest.images else None
            carried = {INIT, FINAL} | ({image} if image else set())
        problems = []
        # the file's own fields, as the bpb that wrote it hashed them (not the model's defaults)
        if content_hash(manifest_file(self.root)[0] or {}) != self.manifest.dataset_hash:
            problems.append(f"{MANIFEST}: dataset_hash does not match the manifest's content")
        for name, digest in sorted(self.manifest.files.items()):
            target = self.root / name
            if not inside(name):
                problems.append(f"{MANIFEST}: files: {name!r} is not a path inside the dataset")
            elif not target.is_file():
                problems.append(f"{name}: missing")
            elif hashlib.sha256(target.read_bytes()).hexdigest() != digest:
                problems.append(f"{name}: content differs from the hash in {MANIFEST}")
        problems += _folder_problems(self.root, _read_index(self.root / INDEX))
        path = self.root / CHECKSUMS
        try:
            lines = path.read_text(encoding="utf-8").splitlines()
        except (OSError, ValueError) as exc:
            raise BadInput(
                f"{path}: cannot read: {getattr(exc, 'strerror', None) or exc}"
            ) from None
        for number, line in enumerate(lines, 1):
            entry = parse_line(line)
            if entry is None:
                problems.append(
                    f"{CHECKSUMS}: line {number}: not '<sha256>  <path inside the dataset>'"
                )
                continue
            digest, rel = entry
            if carried is not None and PurePosixPath(rel).name not in carried:
                continue
            target = self.root / rel
            if not target.is_file():
                problems.append(f"{rel}: missing")
            elif hashlib.sha256(target.read_bytes()).hexdigest() != digest:
                problems.append(f"{rel}: content differs from its checksum")
        return problems


def dataset_keys(root: Path) -> list[SceneKey]:
    """The scenes of the folder ``root``: those its ``index.csv`` lists (a generated dataset),
    else every ``h{t}/scene_{i}`` folder (a hand-made folder of scenes).

    Raises:
        BadInput: ``index.csv`` is corrupt, lists a scene that has no folder, or does not list
            a scene folder that is there: the folder is not the dataset its manifest describes
            (names the first such folder).
    """
    if not (root / INDEX).is_file():
        return list(iter_scene_keys(root))
    listed = _read_index(root / INDEX)
    problems = _folder_problems(root, listed)
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise BadInput(
            f"{root / problems[0]}{more}: the dataset no longer matches its {INDEX}; "
            "restore it or generate it again"
        )
    return listed


def _folder_problems(root: Path, listed: Sequence[SceneKey]) -> list[str]:
    """Scene folders ``listed`` but absent, and present but not ``listed`` (relative paths)."""
    try:
        present = set(iter_scene_keys(root))
    except OSError as exc:
        raise BadInput(f"{root}: cannot list scene folders: {exc.strerror or exc}") from None
    wanted = set(listed)
    missing = [f"{k.dir(Path())}: listed in {INDEX} but missing" for k in sorted(wanted - present)]
    extra = [
        f"{k.dir(Path())}: a scene folder {INDEX} does not list" for k in sorted(present - wanted)
    ]
    return missing + extra


def load_dataset(
    root: str | Path,
    horizons: Sequence[float] | None = None,
    limit: int | None = None,
    *,
    registry: Registry | None = None,
) -> Dataset:
    """Open the dataset folder ``root`` (optionally narrowed with :meth:`Dataset.select`); a
    Hugging Face export of one (``bpb export --format hf``) opens as the folder it came from.

    Raises:
        BadInput: ``root`` is not a dataset, its manifest or index is corrupt, or its scene
            family is not installed.
    """
    source = Path(root)
    root = resolve_data(source)
    manifest = read_manifest(root)
    family = dataset_family(manifest, root, registry)
    export = source if root != source else None
    dataset = Dataset(root, manifest, tuple(_read_index(root / INDEX)), family, export)
    return dataset.select(horizons, limit)


def read_manifest(root: Path) -> DatasetManifest:
    """The validated ``dataset.json`` of ``root``.

    Raises:
        BadInput: There is none, or it is invalid.
    """
    if not (root / MANIFEST).is_file():
        raise BadInput(f"{root}: not a bpb dataset (no {MANIFEST}); create one with bpb generate")
    return read_model(root / MANIFEST, DatasetManifest)


def manifest_file(root: Path) -> tuple[dict[str, Any] | None, str | None]:
    """The JSON object of ``root/dataset.json`` and the SHA-256 of its bytes, from one read
    (``None`` for both when there is none), checked where the lenient readers look (a hand-made
    folder's manifest may hold only a few keys): no NaN or infinity anywhere; ``dataset_hash``,
    when there, a string; ``config``, when there, an object whose ``family``, when there, is a
    non-empty string. A manifest that names its ``format`` (one ``bpb generate`` wrote) is
    checked whole, as :func:`read_manifest` does.

    Raises:
        BadInput: The file cannot be read, is not a JSON object, or one of those fields is
            wrong (names the file and the field).
    """
    path = root / MANIFEST
    try:
        raw = path.read_bytes()
        data = json.loads(raw.decode("utf-8"))
    except FileNotFoundError:
        return None, None
    except (OSError, ValueError) as exc:
        why = getattr(exc, "strerror", None) or exc
        raise BadInput(f"{path}: cannot read dataset manifest: {why}") from None
    if not isinstance(data, dict):
        raise BadInput(
            f"{path}: not a dataset manifest: a JSON object ({{...}}) expected, "
            f"not {_json_kind(data)}"
        )
    found = non_finite(data)
    if found is not None:
        raise BadInput(f"{path}: {found[0]}: not a finite number (NaN and infinity are not JSON)")
    recorded = data.get("dataset_hash")
    if recorded is not None and not isinstance(recorded, str):
        raise BadInput(f"{path}: dataset_hash: a string expected, not {_json_kind(recorded)}")
    if "config" in data:
        config = data["config"]
        if not isinstance(config, dict):
            raise BadInput(
                f"{path}: config: an object of the scene family's settings expected, "
                f"not {_json_kind(config)}"
            )
        name = config.get("family")
        if "family" in config and not (isinstance(name, str) and name):
            raise BadInput(
                f"{path}: config.family: a scene family name expected, not {_json_kind(name)}"
            )
    if "format" in data:  # written by bpb generate: every field it writes is checked
        validate_mapping(DatasetManifest, data, str(path))
    return data, hashlib.sha256(raw).hexdigest()


def _json_kind(value: object) -> str:
    """``a list``, ``the number 3``: what a JSON value is, for a message."""
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return "a list"
    if value is None:
        return "null"
    text = json.dumps(value)
    return f"{text[:40]}..." if len(text) > 40 else text


@dataclass(frozen=True)
class DataFolder:
    """A folder of scenes as a command reads it, once (:func:`open_folder`): its
    ``dataset.json`` and the scene family that made it, passed down to every check and record
    of a run instead of each reading the file again.

    Attributes:
        recorded: The manifest's fields as written, checked (:func:`manifest_file`; ``None``:
            a hand-made folder of scenes without one).
        digest: The SHA-256 of the manifest's bytes (``None`` without one).
        family: The scene family it names (the default family when it names none).
        origin: Who supplied the family (``Registered.origin``), for one-line plugin errors.
    """

    root: Path
    recorded: dict[str, Any] | None
    digest: str | None
    family: SceneFamily
    origin: str

    def config(self) -> Any:
        """The family's config the dataset was made with (its defaults for a folder without a
        manifest, or a manifest without a config).

        Raises:
            BadInput: The config is not valid for the family (names the file and the field).
            PluginBug: The family's ``load_config()`` raised anything else or returned
                something other than its ``config_model``
                (:func:`~bpb_core.plugin_calls.loaded_config`).
        """
        config = self.recorded.get("config") if self.recorded is not None else None
        if not isinstance(config, dict):
            return loaded_config(self.family, self.origin, None)
        fields = getattr(self.family.config_model, "model_fields", {})
        try:
            return loaded_config(
                self.family,
                self.origin,
                {k: v for k, v in config.items() if k != "family" or k in fields},
            )
        except BadInput as exc:  # the family names the field ("config: balls: ..."), not the file
            raise BadInput(f"{self.root / MANIFEST}: {exc}") from None

    def simulator(self) -> str:
        """The simulator the dataset was made with: the one its config names, checked
        (:func:`~bpb_core.plugin_calls.simulator_named`).

        Raises:
            BadInput: As :meth:`config`.
            PluginBug: The family's ``load_config()`` or ``simulator_name()`` raised or
                returned the wrong type, naming ``origin``.
        """
        return simulator_named(self.family, self.origin, self.config())

    def simulator_spec(self) -> SimulatorSpec:
        """:meth:`simulator` parsed into its name and options (``pymunk:dt=0.0005``).

        Raises:
            BadInput: As :meth:`simulator`, or the spec does not parse (names the manifest's
                ``config: simulator``).
        """
        return parse_spec(self.simulator(), f"{self.root / MANIFEST}: config: simulator")


def open_folder(data: Path | DataFolder, registry: Registry | None = None) -> DataFolder:
    """The folder of scenes ``data`` read once (a :class:`DataFolder` is returned as it is).

    Raises:
        BadInput: ``dataset.json`` is not a valid manifest (:func:`manifest_file`), or the
            family it names is not installed.
    """
    if isinstance(data, DataFolder):
        return data
    from bpb_core.registry import make_registry

    registry = registry if registry is not None else make_registry()
    recorded, digest = manifest_file(data)
    family = _installed_family(_named_family(recorded), data, registry)
    entry = registry.entries("scene_family").get(family.name)
    origin = entry.origin if entry is not None else object_origin(family)
    return DataFolder(data, recorded, digest, family, origin)


def dataset_family(
    manifest: DatasetManifest | None, root: Path, registry: Registry | None = None
) -> SceneFamily:
    """The scene family that made the dataset at ``root``: the one its manifest names, else
    the default family (a folder of scenes with no manifest).

    Raises:
        BadInput: ``dataset.json`` is not a valid manifest, or the family is not installed.
    """
    from bpb_core.registry import make_registry

    registry = registry if registry is not None else make_registry()
    name = manifest.family if manifest is not None else _named_family(manifest_file(root)[0])
    return _installed_family(name, root, registry)


def _named_family(recorded: dict[str, Any] | None) -> str | None:
    """The scene family a manifest's fields name (``config.family``), if any."""
    config = recorded.get("config") if recorded is not None else None
    name = config.get("family") if isinstance(config, dict) else None
    return name if isinstance(name, str) and name else None


def _installed_family(name: str | None, root: Path, registry: Registry) -> SceneFamily:
    if name is None:
        name = registry.default_family()
    elif name not in registry.names("scene_family"):
        known = ", ".join(registry.names("scene_family")) or "none"
        raise BadInput(
            f"{root / MANIFEST}: config.family: scene family {name!r} is not installed "
            f"(installed: {known})"
        )
    return registry.scene_family(name)


def _read_index(path: Path) -> list[SceneKey]:
    try:
        text = path.read_text(encoding="utf-8-sig")  # a spreadsheet may add a BOM
    except OSError as exc:
        raise BadInput(f"{path}: cannot read: {exc.strerror or exc}") from None
    except ValueError as exc:  # not UTF-8
        raise BadInput(f"{path}: not UTF-8 text: {exc}") from None
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
    if len(set(keys)) != len(keys):
        twice = next(k for k in keys if keys.count(k) > 1)
        raise BadInput(f"{path}: scene {twice.scene_id} is listed twice")
    return sorted(keys)
