"""One scene of a dataset as the library hands it out: its id, its files, its state and truth;
and the check that a scene file read for use is the file that was generated.

:class:`DatasetScene` is what iterating or indexing a :class:`~bpb_core.dataset.reader.Dataset`
yields. It reads ``init.json`` and ``final.json`` on first use (with the scene family's models)
and names every image file of the scene, so embedding code never spells a file name itself.

``bpb run``, ``bpb report``, ``bpb export`` and the library read a scene's files through
:func:`read_scene_file` (JSON through :func:`read_scene_model`), so a file changed after
generation (an edited ``final.json`` would silently change every score) is refused in one line
naming it, instead of being used. Folders without ``checksums.sha256`` (hand-made scenes) and
files it does not list are read unchecked; a ``checksums.sha256`` that cannot be read or holds a
line that is no checksum is refused naming it (else it would turn the check off).
``Dataset.verify()`` lists every difference at once.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING, Any, TypeVar

from pydantic import BaseModel

from bpb_core.dataset.manifest import CHECKSUMS
from bpb_core.errors import BadInput
from bpb_core.layout import FINAL, INIT, SceneKey
from bpb_core.validated_files import read_bytes, read_model

if TYPE_CHECKING:
    from bpb_core.interfaces import SceneFamily

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
            generation (:mod:`bpb_core.dataset.scene_entry`).
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
