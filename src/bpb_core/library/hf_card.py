"""The README dataset card of a Hugging Face export: YAML front matter and a Markdown body.

The front matter is what the Hub and ``datasets`` read: license, one config whose splits are
the horizons (``data/h3-*``), the features and the rows per split. The body says what a row is,
how to load it, how the data was generated (config and seed, from ``dataset.json``), which
simulator made the ground truth and what to cite; the family's words come from its
:class:`~bpb_core.capabilities.DescribesDataset`.
YAML is written by hand with JSON scalars (valid YAML), so the export needs no YAML library.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from bpb_core.capabilities import DescribesDataset
from bpb_core.dataset.reader import dataset_simulator_spec
from bpb_core.errors import UnknownName
from bpb_core.version import __version__

if TYPE_CHECKING:
    from bpb_core.dataset.reader import Dataset
    from bpb_core.registry import Registry

_FEATURE_NAMES = {"Image": "image"}


def card_text(
    dataset: Dataset,
    features: Mapping[str, Mapping[str, str]],
    splits: Mapping[str, tuple[int, int]],
    tasks: Sequence[str],
    registry: Registry,
) -> str:
    """The whole README.md of the export."""
    words = dataset.family.dataset_card() if isinstance(dataset.family, DescribesDataset) else {}
    return "\n".join(
        [
            "---",
            *_front_matter(dataset, words, features, splits),
            "---",
            "",
            *_body(dataset, words, splits, tasks, _truth(dataset, registry)),
        ]
    )


def _truth(dataset: Dataset, registry: Registry) -> list[str]:
    """Which simulator made the ground truth, as the config names it, and what it is (its
    registered summary): the family's words hold for every simulator, and only the simulator
    knows whether its truth is exact or stepped."""
    origin = registry.origin("scene_family", dataset.family.name)
    spec = dataset_simulator_spec(dataset.root, dataset.family, origin)
    try:
        summary = registry.get("simulator", spec.name).info.summary
    except UnknownName:
        summary = ""
    what = f": {summary.rstrip('.')}." if summary else "."
    return ["## Ground truth", "", f"Computed by the simulator `{spec.spec}`{what}", ""]


def _front_matter(
    dataset: Dataset,
    words: Mapping[str, Any],
    features: Mapping[str, Mapping[str, str]],
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
    for name, feature in features.items():
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
