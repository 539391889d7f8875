"""Reading run folders and the ground truth they were run against.

A run folder holds ``run.json`` (adapter spec, model id, tasks, options, dataset path) and one
answer file per (scene, task). The dataset path is read from ``data`` or ``dataset`` (a string,
or an object with a ``path``); a relative path is tried against the run folder, its parents and
the working directory. The scenes a run was expected to answer are the dataset's scenes,
restricted to the run's ``horizons`` and, per horizon, to its first ``limit`` indices (the
runner's own selection rule, :func:`bpb_core.layout.select_keys`). Scenes and ground truth are
read with the models of the dataset's scene family.

Inspect AI logs of bpb's tasks are read as run folders too, so that one report compares models
run with ``bpb run`` and with ``inspect eval bpb/...``. A log of a bpb task records in its task
metadata the dataset (``bpb_dataset``, its hash, the horizons and limit asked) and, per sample,
the scene, the task and bpb's own score (the parsed answer and its status).
:func:`with_inspect_runs` turns every such log among the paths given to ``bpb report`` /
:func:`~bpb_core.results.frames.load_results` into a run folder in the cache
(``$BPB_CACHE_DIR/inspect/...``, see :func:`cache_folder`): the logs of one model on one dataset
and input mode become one run (the newest log wins for a task asked twice), whose answer files
are scored like any run's. Reading logs needs ``inspect_ai`` (``pip install 'bpb[inspect]'``),
imported only when a log is given.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import shutil
import tempfile
import threading
import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.dataset.reader import DataFolder, cache_root, dataset_keys, open_folder, read_truth
from bpb_core.errors import BadInput
from bpb_core.layout import RUN_MANIFEST, SceneKey, iter_scene_keys, select_keys
from bpb_core.model_calls import valid_unicode
from bpb_core.run_folder import (
    REPLIED,
    AnswerRecord,
    UsageRecord,
    answer_path,
    live_run,
    read_manifest as read_run_manifest,
    write_answer,
    write_manifest,
)

if TYPE_CHECKING:
    from bpb_core.interfaces import SceneFamily
    from bpb_core.registry import Registry


LOG_SUFFIXES = (".eval", ".json")
PREFIX = "inspect"
_HELD: dict[str, int] = {}
"""Per ``where``: the descriptor holding this process's shared lock on its cache folder."""
_GUARD = threading.Lock()


def with_inspect_runs(items: Iterable[Path | str]) -> list[Path]:
    """``items`` with Inspect logs (files, or folders holding ``*.eval`` logs) replaced by the
    run folders made from them; everything else is kept as given.

    Raises:
        BadInput: A log given by name is not a log of a bpb task, or cannot be read.
    """
    kept: list[Path] = []
    named: list[Path] = []
    found: list[Path] = []
    for item in map(Path, items):
        if item.is_file() and item.suffix in LOG_SUFFIXES and item.name != RUN_MANIFEST:
            named.append(item)
        elif item.is_dir() and not (item / RUN_MANIFEST).is_file():
            logs = sorted(item.glob("*.eval"))
            found += logs
            if not logs or any((p / RUN_MANIFEST).is_file() for p in item.iterdir()):
                kept.append(item)
        else:
            kept.append(item)
    if not named and not found:
        return kept
    return kept + runs_from_logs(named, found)


def runs_from_logs(named: list[Path], found: list[Path]) -> list[Path]:
    """Run folders for the bpb logs among ``named`` (each must be one) and ``found``."""
    logs = [(path, _read(path)) for path in [*named, *found]]
    for path, log in logs[: len(named)]:
        if _bpb(log) is None:
            raise BadInput(f"{path}: not an Inspect log of a bpb task (inspect eval bpb/...)")
    groups: dict[tuple[str, str, str], list[Any]] = {}
    for _, log in sorted(logs, key=lambda pair: str(pair[1].eval.created)):
        meta = _bpb(log)
        if meta is not None and log.samples:
            key = (log.eval.model, meta["bpb_dataset"], str(meta.get("bpb_input_mode")))
            groups.setdefault(key, []).append(log)
    paths = [path for path, _ in logs]

    def build(folder: Path) -> None:
        for key, group in sorted(groups.items()):
            _write_run(folder, key, group)

    # which logs: their folders (a new log there replaces the cache folder); and the logs as
    # they are now: their paths, sizes and modification times
    where = _digest(sorted({str(path.resolve().parent) for path in paths}))
    stats = [(path.resolve(), path.stat()) for path in paths]
    state = _digest(sorted(f"{p}\t{s.st_size}\t{s.st_mtime_ns}" for p, s in stats))
    root = cache_folder(where, state, build)
    return [root / _run_name(key) for key in sorted(groups)]


def _digest(lines: list[str]) -> str:
    return hashlib.sha256("\n".join(lines).encode()).hexdigest()[:16]


def _read(path: Path) -> Any:
    try:
        from inspect_ai.log import read_eval_log
    except ImportError:
        raise BadInput(
            f"{path}: reading Inspect logs needs inspect_ai: pip install 'bpb[inspect]'"
        ) from None
    try:
        return read_eval_log(str(path))
    except Exception as exc:  # Inspect raises several types for a bad log
        raise BadInput(f"{path}: cannot read Inspect log: {exc}") from None


def _bpb(log: Any) -> dict[str, Any] | None:
    meta = log.eval.metadata or {}
    return meta if isinstance(meta, dict) and meta.get("bpb_dataset") else None


def _run_name(key: tuple[str, str, str]) -> str:
    model, _, mode = key
    slug = "".join(c if c.isalnum() or c in "-_." else "_" for c in f"{PREFIX}:{model}")
    return slug if mode == "image" else f"{slug}_{mode}"


def _write_run(root: Path, key: tuple[str, str, str], logs: list[Any]) -> Path:
    model, data, _ = key
    adapter = f"{PREFIX}:{model}"
    run_dir = root / _run_name(key)
    tasks: dict[str, None] = {}
    for log in logs:  # oldest first: a later log's answer replaces an earlier one
        meta = log.eval.metadata
        tasks.update(dict.fromkeys(meta["bpb_task_names"]))
        for sample in log.samples:
            record = _record(sample, adapter)
            if record is not None:
                write_answer(run_dir, SceneKey(record.horizon, record.index), record)
    meta = logs[-1].eval.metadata
    manifest = {
        "adapter": adapter,
        "model_id": model,
        "data": data,
        "dataset_hash": meta.get("bpb_dataset_hash"),
        "tasks": list(tasks),
        "horizons": meta.get("bpb_horizons"),
        "limit": meta.get("bpb_limit"),
        "options": {"input_mode": meta.get("bpb_input_mode")},
        "source": "inspect_ai",
        "inspect_logs": [str(log.location) for log in logs],
    }
    write_manifest(run_dir, manifest)
    return run_dir


def _record(sample: Any, adapter: str) -> AnswerRecord | None:
    meta = sample.metadata or {}
    if "scene_id" not in meta or "task" not in meta:
        return None
    score = next(iter((sample.scores or {}).values()), None)
    extra = (score.metadata or {}) if score is not None else {}
    status = str(extra.get("status") or "api_error")
    choices = sample.output.choices if sample.output else None  # none when the call failed
    failed = None if sample.error is None else str(sample.error.message)
    usage = UsageRecord()
    for used in (sample.model_usage or {}).values():
        usage.input_tokens += used.input_tokens or 0
        usage.output_tokens += used.output_tokens or 0
        usage.reasoning_tokens += used.reasoning_tokens or 0
        usage.cached_tokens += used.input_tokens_cache_read or 0
    return AnswerRecord(
        scene_id=str(meta["scene_id"]),
        horizon=float(meta["horizon"]),
        index=int(meta["index"]),
        task=str(meta["task"]),
        adapter=adapter,
        status=status if status in REPLIED else "api_error",
        answer=json.loads(score.answer) if score is not None and score.answer else None,
        rule=extra.get("rule"),
        finish_reason=str(choices[0].stop_reason) if choices else None,
        attempts=1,
        usage=usage,
        latency=float(sample.total_time or 0.0),
        error=(score.explanation if score is not None else None) or failed,
        input_mode=str(meta.get("input_mode") or "image"),
        cot=bool(meta.get("cot")),
    )


def cache_folder(where: str, state: str, build: Callable[[Path], None]) -> Path:
    """The folder ``<where>-<state>`` under ``$BPB_CACHE_DIR/inspect`` (``where`` names the logs'
    folders, ``state`` the logs as they are), made by ``build`` in a hidden folder renamed into
    place whole (a reader never sees half of one) unless made already. The process holds a
    shared ``flock`` on it until it exits or reads a newer state of the same logs (``bpb view``
    reads answer files long after loading them); the other states no process holds are then
    removed (the system drops a dead process's locks).

    Raises:
        OSError: The folder keeps being removed while taken (other processes reading other
            states of the same logs, over and over).
    """
    base = cache_root() / PREFIX
    root = base / f"{where}-{state}"
    for _ in range(5):
        if not root.is_dir():
            _build(root, build)
        handle = _hold(root)
        if handle is not None:
            _keep(where, handle)
            _prune(base, where, root.name)
            return root
    raise OSError(f"{root}: removed each time it was made; try again")


def _build(root: Path, build: Callable[[Path], None]) -> None:
    root.parent.mkdir(parents=True, exist_ok=True)
    building = Path(tempfile.mkdtemp(prefix=f".{root.name}.", dir=root.parent))
    try:
        build(building)
        with contextlib.suppress(OSError):  # another caller made it meanwhile, from the same logs
            building.rename(root)  # whole or not at all
    finally:
        shutil.rmtree(building, ignore_errors=True)


def _hold(root: Path) -> int | None:
    """A descriptor of ``root`` with a shared lock on it; ``None`` when ``root`` was removed
    (or replaced) before the lock was taken."""
    try:
        handle = os.open(root, os.O_RDONLY | os.O_DIRECTORY)
    except FileNotFoundError:
        return None
    fcntl.flock(handle, fcntl.LOCK_SH)
    try:
        now, held = os.stat(root), os.fstat(handle)
        if (now.st_dev, now.st_ino) == (held.st_dev, held.st_ino):
            return handle
    except FileNotFoundError:
        pass
    os.close(handle)
    return None


def _keep(where: str, handle: int) -> None:
    """Hold ``handle``'s folder for the process, letting go of the one held before for these
    logs."""
    with _GUARD:
        before = _HELD.get(where)
        _HELD[where] = handle
    if before is not None:
        os.close(before)


def _prune(base: Path, where: str, keep: str) -> None:
    """Remove the other states of ``where`` that no process holds (each taken with an exclusive
    lock first, which fails while a reader holds it)."""
    for path in base.glob(f"{where}-*"):
        if path.name == keep:
            continue
        try:
            handle = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
        except OSError:
            continue  # removed by another reader meanwhile
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            gone = path.with_name(f".{path.name}.{os.getpid()}.gone")
            path.rename(gone)  # out of readers' sight before it is emptied
            shutil.rmtree(gone, ignore_errors=True)
        except OSError:  # in use (BlockingIOError), or taken by another reader
            continue
        finally:
            os.close(handle)


class DuplicateRunWarning(UserWarning):
    """The same run folder was given more than once (under other paths, or both itself and a
    folder holding it); it is counted once."""


class StrayAnswerWarning(UserWarning):
    """A run folder holds answer files its ``run.json`` selection does not ask for (another
    scene, task or epoch: put there by hand, or left by another run); they are left out."""


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
    family: SceneFamily | None = field(default=None, compare=False, repr=False)
    epochs: int = 1
    live: str | None = field(default=None, compare=False)
    """The pid of a ``bpb run`` still running in the folder when it was read, else ``None``."""
    family_origin: str = field(default="", compare=False, repr=False)
    """Who supplied :attr:`family` (``Registered.origin``), for one-line plugin errors."""

    @property
    def baseline(self) -> bool:
        """Whether the run is one of the built-in baselines (``baseline:*``)."""
        return self.adapter.startswith("baseline:")

    @property
    def person(self) -> bool:
        """Whether a person answered the run in the browser (``bpb human``: ``human:<name>``)."""
        return self.adapter.startswith("human:")

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

    def truth(self, key: SceneKey) -> tuple[Any, Any]:
        """The scene and its ground truth (cached until its files change)."""
        assert self.family is not None, "read_run resolves the family"
        models: tuple[Any, Any] = (self.family.scene_model, self.family.truth_model)
        return read_truth(self.dataset, key, *models)


def find_runs(
    paths: Path | str | Iterable[Path | str],
    registry: Registry | None = None,
    folders: Iterable[DataFolder] = (),
) -> list[RunFolder]:
    """Run folders in ``paths`` (each a run folder or a folder of run folders), labelled uniquely.
    Inspect AI logs of bpb tasks (``.eval`` files, or folders of them) count as run folders
    (:func:`with_inspect_runs`). Each run's dataset is read once however many runs
    answered it; ``folders``: datasets the caller has read already.

    Raises:
        BadInput: A path does not exist or holds no run folder.
    """
    items = with_inspect_runs([paths] if isinstance(paths, (str, Path)) else list(paths))
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
    found = _once(found)
    labels = _labels(found)
    known = {folder.root.resolve(): folder for folder in folders}  # each dataset read once
    runs = [
        read_run(path, label, registry, known) for path, label in zip(found, labels, strict=True)
    ]
    return _not_copies(runs)


def _not_copies(runs: list[RunFolder]) -> list[RunFolder]:
    """Each run once, though copied to another folder: a run folder whose ``run.json`` is the
    same as an earlier one's, down to when it started and finished, is a copy of it (bpb never
    writes two such), and is left out with one :class:`DuplicateRunWarning`; ranked as a second
    run, it would look like a second model agreeing with the first. Hand-made manifests (no
    ``started``) are never taken for copies."""
    first: dict[str, RunFolder] = {}
    kept: list[RunFolder] = []
    for run in runs:
        if "started" not in run.manifest:
            kept.append(run)
            continue
        same = first.setdefault(json.dumps(run.manifest, sort_keys=True), run)
        if same is run:
            kept.append(run)
            continue
        warnings.warn(
            f"{run.path}: a copy of the run in {same.path} (the same run.json, started "
            f"{run.manifest['started']}); counted once",
            DuplicateRunWarning,
            stacklevel=3,
        )
    return kept


def _once(found: list[Path]) -> list[Path]:
    """Each run folder once (by its resolved path, in the order first given), with one
    :class:`DuplicateRunWarning` per run given more than once: counted twice, its calls, tokens,
    cost and units would be summed twice and its bootstrap intervals narrowed."""
    first: dict[Path, list[Path]] = {}
    for path in found:
        first.setdefault(path.resolve(), []).append(path)
    for given in first.values():
        if len(given) > 1:
            warnings.warn(
                f"{given[0]}: the same run folder given {len(given)} times (by other paths, "
                "or inside a folder also given); counted once",
                DuplicateRunWarning,
                stacklevel=3,
            )
    return [given[0] for given in first.values()]


def _labels(paths: list[Path]) -> list[str]:
    names = [p.name for p in paths]
    if len(set(names)) == len(names):
        return names
    return [f"{p.parent.name}/{p.name}" if names.count(p.name) > 1 else p.name for p in paths]


def read_run(
    path: Path,
    label: str | None = None,
    registry: Registry | None = None,
    known: dict[Path, DataFolder] | None = None,
) -> RunFolder:
    """Read ``path/run.json`` and work out the scenes the run was expected to answer.
    ``known``: dataset folders already read, by resolved path (the run's is added)."""
    manifest = read_run_manifest(path)
    if manifest is None:
        raise BadInput(f"{path / RUN_MANIFEST}: no run manifest")
    # shown in tables, charts and pages: a lone surrogate (a "\udc80" escape in run.json, or a
    # folder name that is not UTF-8) has no UTF-8 form and would fail them all
    adapter = valid_unicode(str(manifest.get("adapter") or manifest.get("spec") or path.name))
    model = valid_unicode(str(manifest.get("model_id") or manifest.get("model") or adapter))
    dataset = _dataset_path(manifest, path)
    known = known if known is not None else {}
    if dataset not in known:
        known[dataset] = open_folder(dataset, registry)
    folder = known[dataset]
    _same_dataset(manifest, folder, path)
    tasks = _option(manifest, "tasks")
    if not tasks:
        raise BadInput(f"{path / RUN_MANIFEST}: tasks: the run records no tasks")
    keys = _expected_keys(manifest, dataset, path)
    names = tuple(str(t) for t in tasks)
    label = valid_unicode(label or path.name)
    dropped = manifest.get("dropped_params") or []
    if dropped:  # the model did not get what the protocol asked (temperature 0 above all)
        label = f"{label} [dropped: {', '.join(map(str, dropped))}]"
    epochs = _option(manifest, "epochs")
    epochs = epochs if isinstance(epochs, int) and epochs >= 1 else 1
    return RunFolder(
        path, label, adapter, model, names, dataset, keys, manifest, folder.family, epochs,
        live_run(path), folder.origin,
    )  # fmt: skip


def _same_dataset(manifest: dict[str, Any], folder: DataFolder, run_path: Path) -> None:
    """Refuse a run whose dataset was regenerated since: its answers are about other scenes
    and scoring them against the new ground truth would mix two datasets silently."""
    recorded = manifest.get("dataset_hash")
    current = folder.recorded.get("dataset_hash") if folder.recorded is not None else None
    if isinstance(recorded, str) and isinstance(current, str) and recorded != current:
        raise BadInput(
            f"{run_path / RUN_MANIFEST}: dataset_hash {recorded[:12]} but {folder.root} now holds "
            f"dataset {current[:12]} (regenerated since the run?): point data at the dataset "
            "the run answered"
        )


def _option(manifest: dict[str, Any], name: str) -> Any:
    options = manifest.get("options")
    return manifest.get(name, options.get(name) if isinstance(options, dict) else None)


def _dataset_path(manifest: dict[str, Any], run_path: Path) -> Path:
    value = manifest.get("data", manifest.get("dataset"))
    if isinstance(value, dict):
        value = value.get("path")
    if not isinstance(value, str) or not value:
        raise BadInput(f"{run_path / RUN_MANIFEST}: data: no dataset path recorded")
    raw = Path(value)
    near = [run_path / raw, run_path.parent / raw, raw, run_path.parent.parent / raw]
    for candidate in [raw] if raw.is_absolute() else near:
        if candidate.is_dir():
            return candidate.resolve()
    raise BadInput(f"{run_path / RUN_MANIFEST}: data: dataset folder {value!r} not found")


def _expected_keys(manifest: dict[str, Any], dataset: Path, run_path: Path) -> tuple[SceneKey, ...]:
    horizons = _option(manifest, "horizons") or None
    limit = _option(manifest, "limit") or None
    keys = select_keys(dataset_keys(dataset), horizons, None if limit is None else int(limit))
    chosen = manifest.get("scene_ids")  # --scenes / --sample: only these were asked
    if isinstance(chosen, list):
        wanted = set(map(str, chosen))
        unknown = sorted(wanted - {key.scene_id for key in keys})
        if unknown:
            raise BadInput(
                f"{run_path / RUN_MANIFEST}: scene_ids: {unknown[0]} is not a scene of {dataset} "
                "in the run's horizons and limit"
            )
        keys = [key for key in keys if key.scene_id in wanted]
    return tuple(keys)


def warn_stray_answers(run: RunFolder) -> None:
    """One :class:`StrayAnswerWarning` when ``run``'s folder holds answer files outside its
    selection (``h{t}/scene_{i}/*.json`` for a scene, task or epoch ``run.json`` does not ask):
    the report leaves them out, so a reader counting the files would otherwise see answers the
    figures silently ignore."""
    epochs = range(1, run.epochs + 1)
    wanted = {
        answer_path(run.path, k, t, e) for k in run.scene_keys for t in run.tasks for e in epochs
    }
    stray = sorted(
        path
        for key in iter_scene_keys(run.path)
        for path in key.dir(run.path).glob("*.json")
        if path not in wanted and not path.name.startswith(".")
    )
    if stray:
        many = f"{len(stray)} answer files" if len(stray) > 1 else "1 answer file"
        warnings.warn(
            f"{run.path}: {many} outside the run's selection (the scenes, tasks and epochs of its "
            f"{RUN_MANIFEST}), e.g. {stray[0]}: left out of the report",
            StrayAnswerWarning,
            stacklevel=3,
        )
