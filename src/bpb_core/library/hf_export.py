"""Export a dataset folder as a Hugging Face dataset: Parquet shards and a dataset card.

One row per scene and task, split by horizon (``data/h3-00000-of-00001.parquet``): the input
image (an ``Image`` feature), the scene id, horizon and index, the task, the exact prompt text
per input mode, the target answer as JSON, the stability flag and annotation, the scene's family
cells of ``index.csv``, and ``init.json`` and ``final.json`` verbatim (so ``bpb run`` can read
the export back, see :mod:`bpb_core.dataset.reader`). ``bpb/`` keeps ``dataset.json``,
``index.csv`` and ``checksums.sha256`` verbatim (so ``verify()`` checks the scene files an export
carries). The same dataset gives the same bytes.

The README dataset card has YAML front matter and a Markdown body. The front matter is what the
Hub and ``datasets`` read: license, one config whose splits are the horizons (``data/h3-*``),
the features and the rows per split. The body says what a row is, how to load it, how the data
was generated (config and seed, from ``dataset.json``), which simulator made the ground truth
and what to cite; the family's words come from its
:class:`~bpb_core.capabilities.DescribesDataset`. YAML is written by hand with JSON scalars
(valid YAML), so the export needs no YAML library.
"""

from __future__ import annotations

import csv
import json
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.capabilities import DescribesDataset
from bpb_core.dataset.manifest import CHECKSUMS, check_unedited
from bpb_core.dataset.reader import (
    DATA,
    SIDE,
    Dataset,
    dataset_keys,
    is_hf_export,
    load_dataset,
    manifest_file,
    open_folder,
    read_scene_file,
    shard_name,
)
from bpb_core.errors import (
    NO_ROOM,
    BadInput,
    UnknownName,
    WriteRefused,
    need_module,
    write_refused,
    writing,
)
from bpb_core.interfaces import InputMode
from bpb_core.layout import (
    FINAL,
    INDEX,
    INIT,
    MANIFEST,
    check_writable_folder,
    horizon_label,
    partial_folder,
)
from bpb_core.model_calls import prompt_text
from bpb_core.version import __version__

if TYPE_CHECKING:
    from bpb_core.dataset.reader import DatasetScene
    from bpb_core.interfaces import Task
    from bpb_core.registry import Registry

_FEATURE_NAMES = {"Image": "image"}
MODES: tuple[InputMode, ...] = ("image", "image+state", "state")
SHARD_ROWS = 1000
ROW_GROUP = 100
# A scene's image repeats in its rows (one per task): a dictionary large enough for a row
# group's distinct images stores each image once instead of once per task.
DICTIONARY_BYTES = 64 * 1024 * 1024
# name -> Hugging Face feature; the order is the column order.
FEATURES: dict[str, dict[str, str]] = {
    "image": {"_type": "Image"},
    "scene_id": {"dtype": "string", "_type": "Value"},
    "horizon": {"dtype": "float64", "_type": "Value"},
    "index": {"dtype": "int64", "_type": "Value"},
    "task": {"dtype": "string", "_type": "Value"},
    **{f"prompt_{m.replace('+', '_')}": {"dtype": "string", "_type": "Value"} for m in MODES},
    "target": {"dtype": "string", "_type": "Value"},
    "stable": {"dtype": "bool", "_type": "Value"},
    "stability": {"dtype": "string", "_type": "Value"},
    "metadata": {"dtype": "string", "_type": "Value"},
    "scene": {"dtype": "string", "_type": "Value"},
    "truth": {"dtype": "string", "_type": "Value"},
}


@dataclass(frozen=True)
class HfExport:
    """What :func:`export_hf` wrote.

    Attributes:
        out: The export folder.
        splits: Rows per split (``h3``), in horizon order.
        files: The Parquet shards, relative to ``out``.
        tasks: The tasks exported.
    """

    out: Path
    splits: dict[str, int]
    files: tuple[str, ...]
    tasks: tuple[str, ...]


def export_hf(
    data: str | Path,
    out: str | Path,
    *,
    tasks: Sequence[str] | None = None,
    shard_rows: int = SHARD_ROWS,
    registry: Registry | None = None,
) -> HfExport:
    """Write ``data`` (a dataset folder) to ``out`` as a Hugging Face dataset.

    Args:
        data: The dataset folder.
        out: The export folder: new, empty, or an earlier export. The export is built in a
            hidden ``.NAME.partial`` folder beside it and moved in at the end, so an export
            that fails leaves an earlier one as it was (and no partial folder).
        tasks: Tasks to export (default: the family's default tasks).
        shard_rows: Rows per Parquet file at most.
        registry: Where the family and tasks come from; default: every installed plugin.

    Raises:
        BadInput: ``data`` is not a dataset, its scene folders do not match its ``index.csv``,
            its ``dataset.json`` was edited after generation, a task is unknown, a scene file
            is missing or damaged, or ``out`` holds other files or cannot be a folder (a file,
            or under one).
        WriteRefused: The system refused a write (a full disk): names the file.
    """
    from bpb_core.registry import make_registry

    registry = registry or make_registry()
    dataset = load_dataset(data, registry=registry)
    dataset_keys(dataset.root)  # scene folders unlike index.csv: refused, as bpb run does
    check_unedited(dataset.root / MANIFEST, manifest_file(dataset.root)[0])  # and an edit
    names = tuple(tasks or registry.tasks_for(dataset.family.name, default_only=True))
    objects = [registry.task(name) for name in names]
    index = csv.DictReader((dataset.root / INDEX).read_text(encoding="utf-8-sig").splitlines())
    drop = {"scene_id", "horizon", "index", "stable"}  # index.csv: only the family's cells kept
    cells = {row["scene_id"]: {k: v for k, v in row.items() if k not in drop} for row in index}
    # a dataset made with images needs each scene's (a missing one is an error naming it)
    images = dataset.family.input_image is not None and dataset.manifest.images
    target = Path(out)
    _check_out(target)
    with partial_folder(target, "bpb export") as partial:
        try:
            with writing(partial):
                (partial / DATA).mkdir()
                (partial / SIDE).mkdir()
            splits: dict[str, tuple[int, int]] = {}  # rows and Arrow bytes per split
            files: list[str] = []
            for horizon in dataset.horizons:
                rows = [
                    _row(scene, task, cells.get(scene.scene_id, {}), images, registry)
                    for scene in dataset.select([horizon])
                    for task in objects
                ]
                written, nbytes = _write_split(partial, horizon_label(horizon), rows, shard_rows)
                splits[horizon_label(horizon)] = (len(rows), nbytes)
                files += written
            _write_side_files(dataset, partial)
            family = dataset.family
            words = family.dataset_card() if isinstance(family, DescribesDataset) else {}
            body = _body(dataset, words, splits, names, _truth(dataset, registry))
            card = "\n".join(["---", *_front_matter(dataset, words, splits), "---", "", *body])
            with writing(partial / "README.md"):
                (partial / "README.md").write_text(card, encoding="utf-8")
            _swap_in(partial, target)
        except WriteRefused as exc:
            kept = f"; {target} is as it was" if target.exists() else ""
            raise WriteRefused(
                f"{exc}; nothing was exported (the unfinished export in {partial} is removed){kept}"
            ) from None
        finally:
            shutil.rmtree(partial, ignore_errors=True)  # a failed export leaves nothing half-made
    return HfExport(
        target, {split: rows for split, (rows, _) in splits.items()}, tuple(files), names
    )


def _check_out(out: Path) -> None:
    """``out`` is, or can be made, a folder to export into (one line naming ``--out``)."""
    if out.exists() and not out.is_dir():
        raise BadInput(f"{out}: --out: not a folder; choose a new folder")
    check_writable_folder(out)
    try:
        busy = out.exists() and any(out.iterdir())
    except OSError as exc:
        raise BadInput(f"{out}: --out: cannot read the folder: {exc.strerror or exc}") from None
    if busy and not is_hf_export(out):
        raise BadInput(f"{out}: --out: not empty and not a bpb export; choose a new folder")


def _swap_in(partial: Path, out: Path) -> None:
    """Put the export built in ``partial`` at ``out``: a new folder is renamed into place; in an
    earlier export only ``data/``, ``bpb/`` and ``README.md`` are replaced (other files, such as
    a Hugging Face repository's ``.git``, stay), the old ones kept until the new ones are in."""
    if not out.exists():
        partial.rename(out)
        return
    names = [DATA, SIDE, "README.md"]
    old = partial / ".old"
    old.mkdir()
    moved: list[tuple[Path, Path]] = []
    try:
        for name in names:
            if (out / name).exists() or (out / name).is_symlink():
                (out / name).rename(old / name)
                moved.append((old / name, out / name))
            (partial / name).rename(out / name)
            moved.append((out / name, partial / name))
    except OSError as exc:
        for there, back in reversed(moved):  # put the earlier export back as it was
            there.rename(back)
        raise BadInput(f"{out}: --out: cannot replace the export: {exc.strerror or exc}") from None


def _row(
    scene: DatasetScene, task: Task, cells: dict[str, str], images: bool, registry: Registry
) -> dict[str, Any]:
    prompts = {
        f"prompt_{mode.replace('+', '_')}": _prompt(task, scene, mode, registry)
        if images or mode == "state"
        else None
        for mode in MODES
    }
    stability = getattr(scene.truth, "stability", None)
    return {
        "image": {"bytes": scene.image_bytes(), "path": _relative(scene.image_path())}
        if images
        else None,
        "scene_id": scene.scene_id,
        "horizon": scene.horizon,
        "index": scene.key.index,
        "task": task.name,
        **prompts,
        "target": json.dumps(task.expected(scene.truth)),
        "stable": scene.stable,
        "stability": None if stability is None else stability.model_dump_json(),
        "metadata": json.dumps(cells),
        "scene": read_scene_file(scene.folder / INIT).decode("utf-8"),
        "truth": read_scene_file(scene.folder / FINAL).decode("utf-8"),
    }


def _relative(image: Path) -> str:
    """``h3/scene_0007/init.png``: where the image lives in the dataset folder."""
    return image.relative_to(image.parents[2]).as_posix()


def _prompt(task: Task, scene: DatasetScene, mode: InputMode, registry: Registry) -> str:
    """The text of the messages ``bpb run`` sends (the image is the ``image`` column)."""
    from bpb_core.library import build_messages

    return prompt_text(build_messages(task, scene, mode, registry=registry), "\n\n")


def _write_split(
    out: Path, split: str, rows: list[dict[str, Any]], size: int
) -> tuple[list[str], int]:
    """Write the shards of ``split``; their names and the split's size in Arrow bytes."""
    hf = "pip install 'bpb[hf]'"
    pa = need_module("pyarrow", "a Hugging Face export", hf)
    pq = need_module("pyarrow.parquet", "a Hugging Face export", hf)

    chunks = [rows[i : i + size] for i in range(0, len(rows), size)] or [[]]
    metadata = {"huggingface": json.dumps({"info": {"features": FEATURES}}, sort_keys=True)}
    schema = pa.schema([(name, _arrow_type(pa, feature)) for name, feature in FEATURES.items()])
    names, nbytes = [], 0
    for number, chunk in enumerate(chunks):
        columns = {name: [row[name] for row in chunk] for name in FEATURES}
        table = pa.table(columns, schema=schema.with_metadata(metadata))
        name = shard_name(split, number, len(chunks))
        with writing(out / name):
            pq.write_table(
                table,
                out / name,
                compression="zstd",
                row_group_size=ROW_GROUP,
                dictionary_pagesize_limit=DICTIONARY_BYTES,
            )
        names.append(name)
        nbytes += table.nbytes
    return names, nbytes


def _arrow_type(pa: Any, feature: dict[str, str]) -> Any:
    if feature["_type"] == "Image":
        return pa.struct([("bytes", pa.binary()), ("path", pa.string())])
    return {"string": pa.string(), "float64": pa.float64(), "int64": pa.int64()}.get(
        feature["dtype"], pa.bool_()
    )


def _write_side_files(dataset: Dataset, out: Path) -> None:
    for name in (MANIFEST, INDEX, CHECKSUMS):
        try:
            shutil.copyfile(dataset.root / name, out / SIDE / name)
        except OSError as exc:
            if exc.errno in NO_ROOM:  # the copy, not the dataset
                raise write_refused(out / SIDE / name, exc) from None
            raise BadInput(
                f"{dataset.root / name}: cannot read: {exc.strerror or exc}; the dataset is "
                "damaged: load_dataset(...).verify() lists what changed"
            ) from None


def _truth(dataset: Dataset, registry: Registry) -> list[str]:
    """Which simulator made the ground truth, as the config names it, and what it is (its
    registered summary): the family's words hold for every simulator, and only the simulator
    knows whether its truth is exact or stepped."""
    spec = open_folder(dataset.root, registry).simulator_spec()
    try:
        summary = registry.get("simulator", spec.name).info.summary
    except UnknownName:
        summary = ""
    what = f": {summary.rstrip('.')}." if summary else "."
    return ["## Ground truth", "", f"Computed by the simulator `{spec.spec}`{what}", ""]


def _front_matter(
    dataset: Dataset,
    words: Mapping[str, Any],
    splits: Mapping[str, tuple[int, int]],
) -> list[str]:
    q = json.dumps
    lines = [f"pretty_name: {q(words.get('pretty_name') or dataset.family.name)}"]
    lines.append(f"license: {q(words.get('license') or 'other')}")
    for key in ("task_categories", "tags"):
        if words.get(key):
            lines += [f"{key}:", *(f"- {q(value)}" for value in words[key])]
    lines += ["configs:", "- config_name: default", "  data_files:"]
    for split in splits:
        lines += [f"  - split: {q(split)}", f"    path: {q(f'data/{split}-*')}"]
    lines += ["dataset_info:", "  features:"]
    for name, feature in FEATURES.items():
        dtype = _FEATURE_NAMES.get(feature["_type"], feature.get("dtype", "string"))
        lines += [f"  - name: {q(name)}", f"    dtype: {q(dtype)}"]
    lines.append("  splits:")
    for split, (rows, nbytes) in splits.items():
        lines += [f"  - name: {q(split)}", f"    num_bytes: {nbytes}", f"    num_examples: {rows}"]
    lines += ["bpb:", f"  version: {q(__version__)}", f"  family: {q(dataset.family.name)}"]
    lines += [f"  seed: {dataset.manifest.seed}", f"  dataset_hash: {q(dataset.dataset_hash)}"]
    return lines


def _body(
    dataset: Dataset,
    words: Mapping[str, Any],
    splits: Mapping[str, tuple[int, int]],
    tasks: Sequence[str],
    truth: list[str],
) -> list[str]:
    manifest = dataset.manifest
    title = words.get("pretty_name") or dataset.family.name
    counts = ", ".join(f"{split}: {rows}" for split, (rows, _) in splits.items())
    lines = [f"# {title}", "", str(words.get("description") or "").strip(), "", *truth]
    lines += [
        "## Rows",
        "",
        f"One row per scene and task ({', '.join(tasks)}); one split per horizon ({counts} rows).",
        "`image` is the input image models are shown; `prompt_image`, `prompt_image_state` and",
        "`prompt_state` are the exact prompt texts bpb sends in each input mode; `target` is the",
        "correct answer as JSON; `stable` and `stability` are the stability annotation;",
        "`metadata` holds the scene's cells of `index.csv`; `scene` and `truth` are the scene's",
        "`init.json` and `final.json`, verbatim. `bpb/` keeps `dataset.json`, `index.csv` and",
        "`checksums.sha256`.",
        "",
        "```python",
        "from datasets import load_dataset",
        "",
        'rows = load_dataset("parquet", data_dir="data")  # or the Hub id / this folder',
        "```",
        "",
        "Run models on it with bpb itself: `bpb run --data THIS_FOLDER --adapter ...` scores",
        "exactly as a run on the source folder.",
        "",
        "## Generation",
        "",
        f"Made by bpb {manifest.versions.get('bpb', '?')} with seed {manifest.seed},",
        f"{manifest.per_horizon} scenes per horizon at horizons "
        f"{', '.join(f'{h:g}' for h in manifest.horizons)} s; dataset hash "
        f"`{dataset.dataset_hash}`. The same seed and config give the same bytes:",
        "",
        "```json",
        json.dumps({"seed": manifest.seed, "config": manifest.config}, indent=2, sort_keys=True),
        "```",
    ]
    if words.get("citation"):
        lines += ["", "## Citation", "", "```bibtex", str(words["citation"]).strip(), "```"]
    return [*lines, ""]
