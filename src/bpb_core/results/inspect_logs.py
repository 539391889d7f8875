"""Inspect AI logs of bpb's tasks, read as run folders so that one report compares models run
with ``bpb run`` and with ``inspect eval bpb/...``.

A log of a bpb task records in its task metadata the dataset (``bpb_dataset``, its hash, the
horizons and limit asked) and, per sample, the scene, the task and bpb's own score (the parsed
answer and its status). :func:`with_inspect_runs` turns every such log among the paths given to
``bpb report`` / :func:`~bpb_core.results.frames.load_results` into a run folder in the cache
(``$BPB_CACHE_DIR/inspect/...``, see :func:`cache_folder`): the logs of one model on one
dataset and input mode become one run (the newest log wins for a task asked twice), whose
answer files are scored like any run's.
Reading logs needs ``inspect_ai`` (``pip install 'bpb[inspect]'``), imported only when a log
is given.
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
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from bpb_core.dataset.hf_import import cache_root
from bpb_core.errors import BadInput
from bpb_core.layout import RUN_MANIFEST, SceneKey
from bpb_core.run_folder import REPLIED, AnswerRecord, UsageRecord, write_answer, write_manifest

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
