"""A dataset's ``checksums.sha256``: its lines, and the check that a scene file read for use is
the file that was generated.

``bpb run``, ``bpb report``, ``bpb export`` and the library read a scene's files through
:func:`read_scene_file` (JSON through :func:`read_scene_model`), so a file changed after
generation (an edited ``final.json`` would silently change every score) is refused in one line
naming it, instead of being used. Folders without ``checksums.sha256`` (hand-made scenes) and
files it does not list are read unchecked; ``Dataset.verify()`` lists every difference at once.
"""

from __future__ import annotations

import functools
import hashlib
import re
from pathlib import Path, PurePosixPath
from typing import TypeVar

from pydantic import BaseModel

from bpb_core.dataset.manifest import CHECKSUMS
from bpb_core.errors import BadInput
from bpb_core.validated_files import read_model

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
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise BadInput(f"{path}: cannot read: {exc.strerror or exc}") from None
    check_recorded(path, data)
    return data


def read_scene_model(path: Path, model: type[M]) -> M:
    """A scene's JSON file read with ``model``; a file that does not validate is named with its
    field first, then one that validates but was changed after generation."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise BadInput(f"{path}: cannot read: {exc.strerror or exc}") from None
    value = read_model(path, model, data)
    check_recorded(path, data)
    return value


def check_recorded(path: Path, data: bytes) -> None:
    """Refuse ``data`` (read from the scene file ``path``) when the dataset's
    ``checksums.sha256`` records another hash for it.

    Raises:
        BadInput: The hashes differ (names the file and what to do).
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
    path = root / CHECKSUMS
    try:
        stat = path.stat()
    except OSError:
        return {}
    return _parse_file(path, stat.st_mtime_ns, stat.st_size, stat.st_ino)


@functools.lru_cache(maxsize=16)
def _parse_file(path: Path, mtime_ns: int, size: int, inode: int) -> dict[str, str]:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, ValueError):
        return {}  # unreadable: Dataset.verify() says so; reading scenes does not depend on it
    parsed = (parse_line(line) for line in lines)
    return {rel: digest for digest, rel in (entry for entry in parsed if entry is not None)}
