"""Read a Hugging Face export of a dataset back as a dataset folder.

``bpb export --format hf`` (:mod:`bpb_core.library.hf_export`) writes Parquet shards under
``data/`` and the manifest, index and checksums verbatim under ``bpb/``. :func:`resolve_data`
turns such a folder into a dataset folder that every reader understands: it unpacks each scene's
``init.json``, ``final.json`` and input image, byte for byte, into a cache folder named by the
export's content (``hf/<digest>`` of :func:`cache_root`), once.
"""

from __future__ import annotations

import hashlib
import math
import os
import shutil
from pathlib import Path

from bpb_core.dataset.manifest import CHECKSUMS
from bpb_core.errors import BadInput, need_module
from bpb_core.layout import FINAL, INDEX, INIT, MANIFEST, SceneKey
from bpb_core.validated_files import read_bytes

DATA = "data"
SIDE = "bpb"
_COLUMNS = ["horizon", "index", "image", "scene", "truth"]


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
        table = pq.read_table(shard, columns=_COLUMNS)
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
