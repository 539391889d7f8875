"""The run folder on disk: answer files, the attempts log and ``run.json``; the one reader and
writer of each, used by the runner and by the results alike.

Layout (mirrors the dataset): ``RUN_DIR/run.json``, ``RUN_DIR/attempts.jsonl`` and one
``RUN_DIR/h{t}/scene_{i:04d}/{task}.json`` per answered (scene, task). Answer files are written
atomically (temporary file, then rename), so a killed run leaves either the whole file or none;
a (scene, task) whose file says it got a reply (:data:`REPLIED`) is complete and never asked
again.
The attempts log is appended and flushed line by line; a torn last line from a killed process is
skipped by readers and closed off before the next append.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated, Any, Literal, get_args

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from bpb_core.errors import BadInput, write_refused, writing
from bpb_core.layout import (
    ATTEMPTS,
    RUN_LOCK,
    RUN_MANIFEST,
    SceneKey,
    check_writable_folder,
    iter_scene_keys,
)
from bpb_core.validated_files import describe_validation_error, validate_mapping

Status = Literal["ok", "parse_error", "refused", "cut", "empty", "api_error"]
"""A pair's end: answered (``ok``); a reply with no answer: unparseable (``parse_error``),
declined by the model or its safety filter (``refused``), cut at the token cap (``cut``), with
no text (``empty``); or no reply (``api_error``, resumable)."""
NoAnswer = Literal["refused", "cut", "empty"]
"""How a reply held no answer to parse (:mod:`bpb_core.runner.call`)."""
NO_ANSWER: tuple[str, ...] = get_args(NoAnswer)
REPLIED: tuple[str, ...] = ("ok", "parse_error", *NO_ANSWER)
"""The statuses of a pair that got a reply: complete, scored (all but ``ok`` as wrong)."""
COMPLETE: frozenset[str] = frozenset(REPLIED)


class UsageRecord(BaseModel):
    """Token counts summed over the attempts of one (scene, task)."""

    model_config = ConfigDict(extra="forbid")

    input_tokens: int = 0
    output_tokens: int = 0
    reasoning_tokens: int = 0
    cached_tokens: int = 0


class AnswerRecord(BaseModel):
    """The content of ``RUN_DIR/h{t}/scene_{i:04d}/{task}.json`` (team contract)."""

    model_config = ConfigDict(extra="forbid")

    scene_id: str
    horizon: float
    index: int
    task: str
    adapter: str
    status: Status
    answer: dict[str, Any] | None = None
    rule: str | None = None
    finish_reason: str | None = None
    attempts: int = 0
    usage: UsageRecord = Field(default_factory=UsageRecord)
    cost: float | None = Field(default=None, ge=0, allow_inf_nan=False)  # USD; None: unknown
    latency: float = 0.0
    error: str | None = None
    input_mode: str = "image"
    cot: bool = False
    epoch: int = 1
    metadata: dict[str, bool | float | str] = Field(default_factory=dict)


def answer_path(run_dir: Path, key: SceneKey, task: str, epoch: int = 1) -> Path:
    """Where the answer of ``task`` (its ``epoch``-th sample) for scene ``key`` lives:
    ``q1.json`` for the first epoch, ``q1.e2.json`` for the second."""
    return key.dir(run_dir) / (f"{task}.json" if epoch == 1 else f"{task}.e{epoch}.json")


def make_run_folder(run_dir: Path) -> None:
    """Create the run folder (and its parents), checked as :func:`check_writable_folder` does."""
    check_writable_folder(run_dir)
    try:
        run_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BadInput(f"{run_dir}: --out: cannot create the folder: {exc.strerror}") from None


_TEMP = re.compile(r"\..+\.(?P<pid>[0-9]+)\.tmp")
"""The temporary file of an atomic write: ``.NAME.PID.tmp`` beside ``NAME``."""


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename, so a reader (or a run
    killed half-way) sees the old file or the new one, never a torn one. A write the system
    refuses (a full disk) is a :class:`WriteRefused` naming ``path``, left as it was."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")  # as _TEMP matches
    try:
        try:
            tmp.write_bytes(data)
        except FileNotFoundError:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp.write_bytes(data)
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise write_refused(path, exc) from None


def remove_stale_temps(run_dir: Path) -> None:
    """Remove the temporary files (:func:`write_bytes_atomic`'s) that writers killed before
    their rename left in ``run_dir`` and its scene folders.

    A file whose writer is still alive (a report writing ``scores.csv`` beside a run) is left
    to it; one that cannot be removed is left as it is (it hides no answer)."""
    for path in (*run_dir.glob(".*.tmp"), *run_dir.glob("h*/scene_*/.*.tmp")):
        found = _TEMP.fullmatch(path.name)
        if found is not None and not _alive(int(found["pid"])):
            with contextlib.suppress(OSError):
                path.unlink()


def _alive(pid: int) -> bool:
    """Whether a process ``pid`` exists (this one included: its writes may be under way)."""
    try:
        os.kill(pid, 0)
    except PermissionError:  # another user's process
        return True
    except (ProcessLookupError, OverflowError):  # OverflowError: past any pid there can be
        return False
    return True


def write_json_atomic(path: Path, data: Any) -> None:
    """Write ``data`` as JSON to ``path`` through a temporary file and a rename."""
    write_bytes_atomic(path, (json.dumps(data, indent=1) + "\n").encode("utf-8"))


def write_answer(run_dir: Path, key: SceneKey, record: AnswerRecord) -> Path:
    """Store one (scene, task) result atomically; returns the file written."""
    path = answer_path(run_dir, key, record.task, record.epoch)
    data = record.model_dump(mode="json")
    if record.epoch == 1:  # files of runs without --epochs stay as they always were
        del data["epoch"]
    if not record.metadata:  # nor do files of adapters without metadata
        del data["metadata"]
    write_json_atomic(path, data)
    return path


def read_answer(path: Path) -> AnswerRecord | None:
    """The record in ``path``, or ``None`` when there is no such file; a :class:`BadInput`
    naming the file when it cannot be read or is not an answer record."""
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise BadInput(f"{path}: cannot read answer file: {exc.strerror or exc}") from None
    try:
        return AnswerRecord.model_validate_json(data)
    except ValidationError as exc:
        raise BadInput(f"{path}: not an answer file: {describe_validation_error(exc)}") from None


def iter_answers(run_dir: Path) -> Iterator[tuple[SceneKey, AnswerRecord]]:
    """Every readable answer file of a run folder, by scene then task name; a torn or foreign
    file is skipped (the runner asks its pair again)."""
    for key in iter_scene_keys(run_dir):
        for path in sorted(key.dir(run_dir).glob("*.json")):
            try:
                record = read_answer(path)
            except BadInput:
                continue
            if record is not None:
                yield key, record


def completed(run_dir: Path) -> set[tuple[str, str]]:
    """``(scene_id, task)`` pairs whose first epoch is finished (``ok`` or ``parse_error``)."""
    return {(s, t) for s, t, e in completed_epochs(run_dir) if e == 1}


def completed_epochs(run_dir: Path) -> set[tuple[str, str, int]]:
    """``(scene_id, task, epoch)`` samples already finished (``ok`` or ``parse_error``)."""
    return {(r.scene_id, r.task, r.epoch) for _, r in iter_answers(run_dir) if r.status in COMPLETE}


class AttemptLog:
    """Append-only JSON-lines log of every model call, flushed after each line (``name``:
    another log of the run folder kept the same way, such as its spending ledger)."""

    def __init__(self, run_dir: Path, name: str = ATTEMPTS) -> None:
        self.path = run_dir / name
        with writing(self.path):
            run_dir.mkdir(parents=True, exist_ok=True)
            self._file = self.path.open("a+b")
            size = self._file.seek(0, os.SEEK_END)
            if size:  # close off a line torn by a killed process
                self._file.seek(size - 1)
                if self._file.read(1) != b"\n":
                    self._file.write(b"\n")
                    self._file.flush()

    def append(self, entry: dict[str, Any]) -> None:
        """Write one attempt and flush it to the operating system.

        A lone surrogate (a reply whose JSON carried ``"\\udc80"``) has no UTF-8 form: it is
        written as its JSON escape, so the line stays valid UTF-8 and reads back the same."""
        line = json.dumps(entry, ensure_ascii=False).encode("utf-8", "backslashreplace")
        with writing(self.path):  # a line the disk cut short is torn: readers skip it
            self._file.write(line + b"\n")
            self._file.flush()

    def close(self) -> None:
        """Close the file."""
        with writing(self.path):
            self._file.close()


def read_attempts(run_dir: Path, name: str = ATTEMPTS) -> Iterator[dict[str, Any]]:
    """Every complete line of the attempts log (or the log ``name``; a torn line from a killed
    run is skipped)."""
    path = run_dir / name
    if not path.exists():
        return
    with path.open("rb") as handle:
        for line in handle:
            try:
                entry = json.loads(line)
            except ValueError:
                continue
            if isinstance(entry, dict):
                yield entry


def live_run(run_dir: Path) -> str | None:
    """The pid of another process running in ``run_dir`` now (it holds the folder's lock,
    :mod:`bpb_core.runner.manifest`), else ``None``.

    A run writes its pid into the lock file and empties it when it ends; a non-empty file is
    probed with a shared lock, which fails while a live run holds its exclusive one (a run
    killed outright leaves its pid, but the system has dropped its lock)."""
    try:
        handle = os.open(run_dir / RUN_LOCK, os.O_RDONLY)
    except OSError:
        return None
    try:
        try:
            pid = os.read(handle, 64).decode("ascii", "replace").strip()
        except OSError:  # not a file (a folder named run.lock): no run can hold it as a lock
            return None
        if not pid or pid == str(os.getpid()):
            return None
        try:
            fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return pid
        fcntl.flock(handle, fcntl.LOCK_UN)
        return None
    finally:
        os.close(handle)


def write_manifest(run_dir: Path, manifest: dict[str, Any]) -> None:
    """Write ``run.json`` atomically."""
    write_json_atomic(run_dir / RUN_MANIFEST, manifest)


def read_manifest(run_dir: Path) -> dict[str, Any] | None:
    """``run.json`` of a run folder, or ``None`` if there is none yet; a :class:`BadInput`
    naming the file when it cannot be read or is not a JSON object."""
    path = run_dir / RUN_MANIFEST
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as exc:
        raise BadInput(f"{path}: cannot read run manifest: {exc}") from None
    if not isinstance(data, dict):
        raise BadInput(f"{path}: expected a JSON object")
    validate_mapping(_ManifestFields, data, str(path))
    return data


Seconds = Annotated[float, Field(gt=0, allow_inf_nan=False)]
Count = Annotated[int, Field(ge=1)]


class RunSelection(BaseModel):
    """The fields of ``run.json`` (top level or under ``options``) that decide which scenes a
    report expects: checked so that a hand-edited value is refused, not read as an empty or
    narrower selection."""

    model_config = ConfigDict(extra="allow", strict=True)

    horizons: list[Seconds] | None = None
    limit: Count | None = None
    epochs: Count | None = None


class _ManifestFields(RunSelection):
    tasks: list[Annotated[str, Field(min_length=1)]] | None = None
    scene_ids: list[str] | None = None
    options: RunSelection | None = None
