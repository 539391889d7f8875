"""Reading run folders and the ground truth they were run against.

A run folder holds ``run.json`` (adapter spec, model id, tasks, options, dataset path) and one
answer file per (scene, task). The dataset path is read from ``data`` or ``dataset`` (a string,
or an object with a ``path``); a relative path is tried against the run folder, its parents and
the working directory. The scenes a run was expected to answer are the dataset's scenes,
restricted to the run's ``horizons`` and, per horizon, to its first ``limit`` indices.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

from bpb_core.errors import BadInput
from bpb_core.layout import FINAL, INIT, RUN_MANIFEST, SceneKey, iter_scene_keys
from bpb_core.scene import FinalState, Scene

DEFAULT_TASKS = ("q1", "q2", "q3")
ANSWER_STATUSES = ("ok", "parse_error", "api_error")


@dataclass(frozen=True)
class RunFolder:
    """One run folder, as far as scoring needs it."""

    path: Path
    label: str
    adapter: str
    model: str
    tasks: tuple[str, ...]
    dataset: Path
    scene_keys: tuple[SceneKey, ...]
    manifest: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    @property
    def baseline(self) -> bool:
        """Whether the run is one of the built-in baselines (``baseline:*``)."""
        return self.adapter.startswith("baseline:")

    @property
    def meta(self) -> dict[str, Any]:
        """The per-run columns of every frame row."""
        return {
            "run": self.label,
            "adapter": self.adapter,
            "model": self.model,
            "baseline": self.baseline,
            "dataset": self.dataset_id,
        }

    @property
    def dataset_id(self) -> str:
        """The dataset's hash from ``run.json`` (its path when no hash is recorded)."""
        return str(self.manifest.get("dataset_hash") or self.dataset)


def find_runs(paths: Path | str | Iterable[Path | str]) -> list[RunFolder]:
    """Run folders in ``paths`` (each a run folder or a folder of run folders), labelled uniquely.

    Raises:
        BadInput: A path does not exist or holds no run folder.
    """
    items = [paths] if isinstance(paths, (str, Path)) else list(paths)
    found: list[Path] = []
    for item in items:
        path = Path(item)
        if (path / RUN_MANIFEST).is_file():
            found.append(path)
            continue
        if not path.is_dir():
            raise BadInput(f"{path}: no such run folder")
        inner = sorted(p for p in path.iterdir() if (p / RUN_MANIFEST).is_file())
        if not inner:
            raise BadInput(f"{path}: not a run folder (no {RUN_MANIFEST}) and holds none")
        found.extend(inner)
    labels = _labels(found)
    return [read_run(path, label) for path, label in zip(found, labels, strict=True)]


def _labels(paths: list[Path]) -> list[str]:
    names = [p.name for p in paths]
    if len(set(names)) == len(names):
        return names
    return [f"{p.parent.name}/{p.name}" if names.count(p.name) > 1 else p.name for p in paths]


def read_run(path: Path, label: str | None = None) -> RunFolder:
    """Read ``path/run.json`` and work out the scenes the run was expected to answer."""
    manifest_path = path / RUN_MANIFEST
    try:
        manifest = json.loads(manifest_path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise BadInput(f"{manifest_path}: cannot read run manifest: {exc}") from None
    if not isinstance(manifest, dict):
        raise BadInput(f"{manifest_path}: expected a JSON object")
    adapter = str(manifest.get("adapter") or manifest.get("spec") or path.name)
    model = str(manifest.get("model_id") or manifest.get("model") or adapter)
    tasks = tuple(str(t) for t in (_option(manifest, "tasks") or DEFAULT_TASKS))
    dataset = _dataset_path(manifest, path)
    keys = _expected_keys(manifest, dataset)
    return RunFolder(path, label or path.name, adapter, model, tasks, dataset, keys, manifest)


def _option(manifest: dict[str, Any], name: str) -> Any:
    options = manifest.get("options")
    if name in manifest:
        return manifest[name]
    return options.get(name) if isinstance(options, dict) else None


def _dataset_path(manifest: dict[str, Any], run_path: Path) -> Path:
    value = manifest.get("data", manifest.get("dataset"))
    if isinstance(value, dict):
        value = value.get("path")
    if not isinstance(value, str) or not value:
        raise BadInput(f"{run_path / RUN_MANIFEST}: data: no dataset path recorded")
    raw = Path(value)
    candidates = [raw] if raw.is_absolute() else [run_path / raw, run_path.parent / raw, raw]
    if not raw.is_absolute():
        candidates.append(run_path.parent.parent / raw)
    for candidate in candidates:
        if candidate.is_dir():
            return candidate.resolve()
    raise BadInput(f"{run_path / RUN_MANIFEST}: data: dataset folder {value!r} not found")


def _expected_keys(manifest: dict[str, Any], dataset: Path) -> tuple[SceneKey, ...]:
    keys = list(iter_scene_keys(dataset))
    horizons = _option(manifest, "horizons")
    if horizons:
        wanted = {float(h) for h in horizons}
        keys = [k for k in keys if k.horizon in wanted]
    limit = _option(manifest, "limit")
    if limit:
        seen: dict[float, int] = {}
        keep: list[SceneKey] = []
        for key in keys:
            seen[key.horizon] = seen.get(key.horizon, 0) + 1
            if seen[key.horizon] <= int(limit):
                keep.append(key)
        keys = keep
    return tuple(keys)


@lru_cache(maxsize=65536)
def read_truth(dataset: Path, key: SceneKey) -> tuple[Scene, FinalState]:
    """The scene and its ground truth (cached; datasets are immutable once written)."""
    folder = key.dir(dataset)
    try:
        scene = Scene.model_validate_json((folder / INIT).read_bytes())
        final = FinalState.model_validate_json((folder / FINAL).read_bytes())
    except OSError as exc:
        raise BadInput(f"{folder}: cannot read ground truth: {exc}") from None
    except ValueError as exc:
        first = str(exc).splitlines()[0]
        raise BadInput(f"{folder}: invalid scene or ground truth: {first}") from None
    return scene, final


def read_answer(folder: str, task: str) -> dict[str, Any]:
    """The answer record of one (scene, task) in the run's scene ``folder``; status ``missing``
    when there is no file. (String paths: this runs once per answer file.)"""
    path = os.path.join(folder, f"{task}.json")
    try:
        with open(path, "rb") as handle:
            record = json.loads(handle.read())
    except FileNotFoundError:
        return {"status": "missing", "answer": None, "attempts": 0}
    except (OSError, ValueError) as exc:
        raise BadInput(f"{path}: cannot read answer file: {exc}") from None
    if not isinstance(record, dict) or record.get("status") not in ANSWER_STATUSES:
        raise BadInput(f"{path}: status: expected ok, parse_error or api_error")
    return record
