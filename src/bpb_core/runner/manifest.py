"""The run folder as a session opens it: ``run.json`` and the folder's lock.

``run.json`` records what a run was asked to do, with what software, and when. Resuming a run
folder with different answer-shaping settings (adapter, its model arguments, dataset, input
mode, chain of thought, force-numeric, temperature, max tokens: every option sent to the
provider) would mix incomparable answers, so it is refused as bad input. The guard is kept
twice: in ``run.json`` (written atomically) and as a configuration hash on every line of the
attempts log, which guards a folder that lost its ``run.json``.

One ``bpb run`` (or ``bpb human`` session) per run folder at a time: two runs writing one folder
would pay every call twice and interleave their answers. The first run holds an exclusive
``flock`` on ``RUN_DIR/run.lock`` (holding its pid) until it ends; a second run on the folder is
refused as bad input naming the holder's pid. The operating system drops the lock when its
process dies, however it dies, so a lock left by a dead run is simply taken over.
"""

from __future__ import annotations

import contextlib
import dataclasses
import fcntl
import hashlib
import json
import os
import platform
import sys
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.dataset.reader import DataFolder, open_folder
from bpb_core.errors import BadInput, WriteRefused, write_refused
from bpb_core.layout import ATTEMPTS, RUN_LOCK, RUN_MANIFEST
from bpb_core.run_folder import (
    AnswerRecord,
    iter_answers,
    read_manifest,
    remove_stale_temps,
    write_manifest,
)
from bpb_core.runner.options import RunOptions
from bpb_core.runner.scenes import dataset_hash
from bpb_core.version import __version__

if TYPE_CHECKING:
    from bpb_core.registry import Registry
    from bpb_core.runner.state import RunState


_GUARDED = (
    "adapter",
    "adapter_settings",
    "dataset_hash",
    "input_mode",
    "cot",
    "force_numeric",
    "temperature",
    "structured_output",
    "max_tokens",
)
_UNGUARDED_SETTINGS = ("api_base",)
# No cap is a setting of its own: a run made without --max-tokens resumed with one is refused.
_NONE_IS_A_VALUE = frozenset({"max_tokens"})


def now() -> str:
    """The current UTC time in ISO 8601."""
    return datetime.now(UTC).isoformat(timespec="seconds")


def _version(distribution: str) -> str | None:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return None


def versions() -> dict[str, Any]:
    """Versions of bpb, Python and the libraries that shape answers or costs."""
    found = {name: _version(name) for name in ("litellm", "pydantic", "numpy", "pluggy")}
    return {
        "bpb": __version__,
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        **{k: v for k, v in found.items() if v},
    }


def _options(options: RunOptions, registry: Registry) -> dict[str, Any]:
    data = dataclasses.asdict(options)
    data["cot"] = {t: options.cot.get(t, registry.task(t).default_cot) for t in options.tasks}
    data["horizons"] = None if options.horizons is None else list(options.horizons)
    data["tasks"] = list(options.tasks)
    return data


def _guarded(manifest: dict[str, Any], key: str) -> Any:
    value = manifest.get(key, manifest.get("options", {}).get(key))
    if key == "adapter_settings" and isinstance(value, dict):  # where it is sent may change
        value = {k: v for k, v in value.items() if k not in _UNGUARDED_SETTINGS}
    return value


def _recorded(manifest: dict[str, Any], key: str) -> bool:
    return key in manifest or key in manifest.get("options", {})


def config_hash(manifest: dict[str, Any]) -> str:
    """A digest of a run's answer-shaping settings; every attempt logged carries it, so the
    attempts log alone can refuse a resume that would mix answers. No output cap adds nothing
    to the digest, so the hashes of runs logged before the cap was guarded still match."""
    shaping = {key: _guarded(manifest, key) for key in _GUARDED}
    if shaping["max_tokens"] is None:
        del shaping["max_tokens"]
    text = json.dumps(shaping, sort_keys=True, default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def _check_resume(run_dir: Path, old: dict[str, Any], new: dict[str, Any]) -> None:
    for key in _GUARDED:
        before = _guarded(old, key)
        after = _guarded(new, key)
        if key == "cot" and isinstance(before, dict) and isinstance(after, dict):
            _check_cot(run_dir, before, after)
        elif _differs(old, key, before, after):
            raise BadInput(
                f"{run_dir / RUN_MANIFEST}: {key}: this folder holds a run with "
                f"{_shown(key, before)}, not {_shown(key, after)}; use another --out to keep "
                "answers comparable"
            )


def _differs(old: dict[str, Any], key: str, before: Any, after: Any) -> bool:
    """Whether a resume changes ``key``; a setting the old run.json does not record (written
    before bpb recorded it) is taken as unchanged."""
    known = before is not None or (key in _NONE_IS_A_VALUE and _recorded(old, key))
    return known and before != after


def _shown(key: str, value: Any) -> str:
    return "no cap" if key in _NONE_IS_A_VALUE and value is None else repr(value)


def _check_cot(run_dir: Path, before: dict[str, Any], after: dict[str, Any]) -> None:
    """Chain of thought is kept per task: a resume may add tasks (with their own setting), but a
    task the folder already holds must keep the setting its answers were given under."""
    for task, cot in after.items():
        if task in before and before[task] != cot:
            raise BadInput(
                f"{run_dir / RUN_MANIFEST}: cot: this folder holds task {task} run with chain of "
                f"thought {_on(before[task])}, not {_on(cot)}; use another --out to keep answers "
                "comparable"
            )


def _on(flag: object) -> str:
    return "on" if flag is True else "off" if flag is False else repr(flag)


def _check_selection(
    run_dir: Path, scene_ids: list[str], options: RunOptions, held: Iterable[AnswerRecord]
) -> None:
    """Refuse a resume whose selection leaves out answers the folder already holds: its
    ``run.json`` would describe fewer scenes, tasks or epochs, and reports would silently drop
    those answers."""
    wanted, tasks = set(scene_ids), set(options.tasks)
    for record in held:
        if record.scene_id in wanted and record.task in tasks and record.epoch <= options.epochs:
            continue
        raise BadInput(
            f"{run_dir}: holds answers outside this selection ({record.scene_id} "
            f"{record.task}, epoch {record.epoch}); resuming with fewer scenes, tasks or epochs "
            "(--horizons, --limit, --scenes, --sample, --tasks, --epochs) would leave them out "
            "of the run and its reports: resume with the same or a wider selection, or use "
            "another --out"
        )


def start_manifest(
    run_dir: Path,
    spec: str,
    data: Path | DataFolder,
    options: RunOptions,
    registry: Registry,
    scenes: int,
    settings: dict[str, Any] | None = None,
    logged: set[str] | None = None,
    scene_ids: list[str] | None = None,
    held: Iterable[AnswerRecord] | None = None,
) -> dict[str, Any]:
    """Write ``run.json`` at the start (or resume) of a run and return its content.

    ``data``: the dataset folder (read here when it is a path). ``settings``: the adapter's,
    checked (:func:`~bpb_core.plugin_calls.described_settings`).
    ``logged`` holds the configuration hashes found in the attempts log; with no ``run.json``
    they alone guard the resume. ``scene_ids`` lists the scenes asked when ``--scenes`` or
    ``--sample`` chose them (the results expect answers for these only); ``held``: the answer
    records already in the folder, if the caller has read them (else they are read here).

    Raises:
        BadInput: The folder holds a run with other answer-shaping settings, or answers
            outside this selection.
    """
    folder = open_folder(data, registry)
    manifest: dict[str, Any] = {
        "adapter": spec,
        "model_id": None,
        "adapter_settings": settings,
        "tasks": list(options.tasks),
        "options": _options(options, registry),
        "dataset": str(folder.root.resolve()),
        "dataset_hash": dataset_hash(folder),
        "scenes": scenes,
        "versions": versions(),
        "plugins": [
            dict(kind=e.info.kind, name=e.info.name, distribution=e.distribution, version=e.version)
            for e in registry
        ],
        "started": now(),
        "finished": None,
        "order_seed": options.seed,
    }
    if options.scenes is not None or options.sample is not None:
        manifest["scene_ids"] = scene_ids
    manifest["config_hash"] = config_hash(manifest)
    old = read_manifest(run_dir)
    if old is None:
        other = sorted((logged or set()) - {manifest["config_hash"]})
        if other:
            raise BadInput(
                f"{run_dir / ATTEMPTS}: holds attempts of another configuration (hash "
                f"{other[0]}, this run {manifest['config_hash']}) and {RUN_MANIFEST} is missing; "
                "use another --out to keep answers comparable"
            )
        manifest["sessions"] = [manifest["started"]]
    else:
        _check_resume(run_dir, old, manifest)
        if scene_ids is not None:
            records = held if held is not None else (r for _, r in iter_answers(run_dir))
            _check_selection(run_dir, scene_ids, options, records)
        manifest["started"] = old.get("started", manifest["started"])
        if isinstance(old.get("order_seed"), int):  # the resumed run goes on in its own order
            manifest["order_seed"] = old["order_seed"]
        manifest["model_id"] = old.get("model_id")
        manifest["dropped_params"] = old.get("dropped_params", [])
        manifest["sessions"] = [*old.get("sessions", []), now()]
    write_manifest(run_dir, manifest)
    return manifest


def finish_manifest(run_dir: Path, manifest: dict[str, Any], state: RunState) -> None:
    """Record the end of this session: time, model id, totals and why it stopped."""
    manifest["finished"] = now()
    manifest["model_id"] = state.model_id or manifest.get("model_id")
    manifest["stopped"] = state.stop_reason
    manifest["dropped_params"] = sorted(set(manifest.get("dropped_params", [])) | state.dropped)
    manifest["last_session"] = {
        "statuses": state.statuses,
        "cost": None if state.unpriced else state.spent,
        "tokens": state.tokens,
        "error": None if state.setup_error is None else str(state.setup_error),
        "budget": state.spending.summary(),
    }
    write_manifest(run_dir, manifest)


@contextmanager
def run_lock(run_dir: Path) -> Iterator[None]:
    """Hold the run folder's lock for the block.

    Taking it, the holder removes the temporary files that killed writers left in the folder
    (:func:`~bpb_core.run_folder.remove_stale_temps`).

    Raises:
        BadInput: Another live process holds the folder (one line naming its pid), or the
            folder cannot hold a lock file (names the path).
        WriteRefused: The system refused to write the lock file (a full disk; names it).
    """
    path = run_dir / RUN_LOCK
    try:
        handle = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as exc:
        raise BadInput(f"{path}: cannot create the run lock: {exc.strerror or exc}") from None
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(handle, 64, 0).decode("ascii", "replace").strip() or "unknown"
            raise BadInput(
                f"{run_dir}: in use by another bpb run or bpb human (pid {holder}); wait for it to "
                "finish or stop it, then re-run to resume"
            ) from None
        try:  # a full disk refuses even these few bytes
            os.ftruncate(handle, 0)
            os.pwrite(handle, f"{os.getpid()}\n".encode("ascii"), 0)
        except OSError as exc:
            raise WriteRefused(
                f"{write_refused(path, exc)}; nothing was sent: make room, then run again"
            ) from None
        remove_stale_temps(run_dir)  # only the lock's holder may: no other writer is there
        try:
            yield
        finally:
            with contextlib.suppress(OSError):  # the lock itself is dropped just below
                os.ftruncate(handle, 0)
            fcntl.flock(handle, fcntl.LOCK_UN)
    finally:
        os.close(handle)
