"""Run folders to pandas: the one place that builds the results frames.

:func:`load_results` reads run folders (``run.json`` plus ``h{t}/scene_{i}/{task}.json``) and
the dataset each one names, cuts every answer into scored units with the task's scorer, scores
them vectorised and returns two frames with explicit dtypes:

- ``units``: one row per scored unit of every expected (run, scene, task); a scene the run has
  no answer file for appears with status ``missing``. Columns: :data:`META_DTYPES`, the
  scorer input (:data:`bpb_core.scored_units.SCORER_INPUT`), each scorer's own columns (NaN on
  other tasks' rows) and the scorer output (``correct``, ``distance``).
- ``calls``: one row per (run, scene, task) with status, tokens, cost, latency, retries and the
  adapter's own measurements (``metadata``, JSON text; see :mod:`bpb_core.results.metadata`).

It also names the suites that apply: installed suites all of whose tasks appear in the units.
Everything else (accuracies, leaderboards, diagnostics, reports) is derived from these frames.
Nothing here prints; :func:`write_scores` writes each run's ``scores.csv`` at the end of
``bpb run``.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.errors import BadInput, ParseFailure, PluginBug, blamed
from bpb_core.interfaces import PromptOptions
from bpb_core.plugin_calls import parsed_answer
from bpb_core.registry import SuiteInfo
from bpb_core.results.reading import RunFolder, find_runs, warn_stray_answers
from bpb_core.results.tables import scene_scores, summary, warning_lines
from bpb_core.run_folder import AnswerRecord, answer_path, read_answer, write_bytes_atomic
from bpb_core.scored_units import (
    SCORER_INPUT,
    SCORER_OUTPUT,
    UnitRow,
    object_origin,
    scored_units,
    unit_rows,
)

if TYPE_CHECKING:
    import pandas as pd

    from bpb_core.dataset.reader import DataFolder
    from bpb_core.interfaces import Scorer, Task
    from bpb_core.layout import SceneKey
    from bpb_core.registry import Registry

META_DTYPES: dict[str, str] = {
    "run": "category",
    "adapter": "category",
    "model": "category",
    "baseline": "bool",
    "dataset": "category",
    "task": "category",
    "horizon": "float64",
    "index": "int32",
    "scene_id": "category",
    "epoch": "int32",
    "stable": "boolean",
    "unstable_reasons": "string",
    "scene_rule": "category",
}
"""Per-row columns of the units frame (``stable`` is NA when not annotated; ``epoch`` is 1
unless the run asked every (scene, task) several times with ``--epochs``; ``unstable_reasons``
lists, comma-separated, the stability conditions an unstable scene fails when its ground truth
says so (:class:`~bpb_core.capabilities.ExplainsInstability`), else empty)."""

CALL_DTYPES: dict[str, str] = {
    **{k: v for k, v in META_DTYPES.items() if k != "scene_rule"},
    "status": "category",
    "attempts": "int32",
    "retries": "int32",
    "input_tokens": "int64",
    "output_tokens": "int64",
    "reasoning_tokens": "int64",
    "cached_tokens": "int64",
    "cost": "float64",
    "latency": "float64",
    "finish_reason": "str",
    "rule": "str",
    "input_mode": "str",
    "cot": "boolean",
    "error": "str",
    "metadata": "str",
}
"""Columns of the calls frame (``cost`` is NaN when unknown, never a made-up 0)."""

_USAGE = ("input_tokens", "output_tokens", "reasoning_tokens", "cached_tokens")


@dataclass(frozen=True)
class Results:
    """The two frames every table and report is derived from, the run folders read and the
    suites whose tasks all appear."""

    units: pd.DataFrame
    calls: pd.DataFrame
    runs: tuple[RunFolder, ...] = ()
    suites: tuple[SuiteInfo, ...] = field(default=())

    @property
    def tasks(self) -> list[str]:
        """Tasks in the units frame, sorted."""
        return sorted(str(t) for t in self.units["task"].unique())

    @cached_property
    def scenes(self) -> pd.DataFrame:
        """The scene scores of :attr:`units` (:func:`~bpb_core.results.tables.scene_scores`),
        computed once: every table of a report derives from them."""
        return scene_scores(self.units)


def load_results(
    run_dirs: Path | str | Iterable[Path | str],
    *,
    registry: Registry | None = None,
    folders: Iterable[DataFolder] = (),
) -> Results:
    """Read and score run folders.

    Args:
        run_dirs: Run folders (holding ``run.json``) or folders of run folders.
        registry: Where scorers, suites and scene families come from; default: all installed
            plugins.
        folders: The datasets of the runs, when the caller has read them (else each is read
            here, once).

    Raises:
        BadInput: No run folder found, a run, answer or ground-truth file cannot be read, or
            no installed scorer scores a task.

    Warns:
        StrayAnswerWarning: A run folder holds answer files outside its selection (left out).
    """
    from bpb_core.registry import make_registry

    registry = registry if registry is not None else make_registry()
    runs = find_runs(run_dirs, registry, folders)
    scorers: dict[str, Scorer] = {}
    origins: dict[str, str] = {}  # who supplied each scorer, for one-line plugin errors
    for run in runs:
        for task in run.tasks:
            if task not in scorers:
                scorers[task] = registry.scorer_for(task)
                origins[task] = registry.scorer_entry(task).origin
    extra = _extra_columns(scorers.values())
    units = _Columns({**META_DTYPES, **SCORER_INPUT, **extra, **SCORER_OUTPUT})
    calls = _Columns(CALL_DTYPES)
    known = registry.names("task")  # the task and who supplied it, to check recorded answers
    tasks = {
        n: (registry.task(n), registry.origin("task", n)) if n in known else None for n in scorers
    }
    for run in runs:
        _read_one(run, scorers, origins, tasks, units, calls)
        warn_stray_answers(run)
    unit_frame = _score(units.frame(), scorers, origins)
    present = set(scorers)
    suites = tuple(s for s in registry.suites() if set(s.weights) <= present)
    return Results(unit_frame, calls.frame(), tuple(runs), suites)


def load_frame(
    run_dirs: Path | str | Iterable[Path | str], *, registry: Registry | None = None
) -> pd.DataFrame:
    """The scored units frame of :func:`load_results` (one row per scored unit)."""
    return load_results(run_dirs, registry=registry).units


def write_scores(
    run_dirs: Sequence[Path], registry: Registry | None = None, folders: Iterable[DataFolder] = ()
) -> pd.DataFrame | None:
    """Write ``scores.csv`` (scored units) into each run folder and return the summary table
    (``None`` when there is nothing to score); ``attrs["warnings"]`` holds the ``(run, line)``
    warnings to print under it (:func:`~bpb_core.results.tables.warning_lines`).
    ``folders``: the runs' datasets, already read."""
    if not run_dirs:
        return None
    results = load_results(list(run_dirs), registry=registry, folders=folders)
    frame = results.units
    written = frame
    if (frame["epoch"] == 1).all():  # without --epochs the file keeps its columns
        written = frame.drop(columns="epoch")
    for run in results.runs:
        text = written[written["run"] == run.label].to_csv(index=False)
        write_bytes_atomic(run.path / "scores.csv", text.encode("utf-8"))
    table = summary(frame, results.suites)
    table.attrs["warnings"] = warning_lines(results)  # what the summary must say
    return table


def _reasons(truth: object, run: RunFolder) -> str:
    """The ground truth's ``unstable_reasons``, comma-separated, checked: a list of strings (a
    string would be joined letter by letter and miscount the report's stable exclusions).

    Raises:
        PluginBug: The ground truth raised or held something else, naming the family's plugin.
    """
    from bpb_core.capabilities import ExplainsInstability

    if not isinstance(truth, ExplainsInstability):
        return ""
    origin = run.family_origin or object_origin(run.family)
    what = f"scene family {getattr(run.family, 'name', '?')!r}: the ground truth's unstable_reasons"
    with blamed(origin, what):
        reasons = truth.unstable_reasons
    if isinstance(reasons, list | tuple) and all(isinstance(r, str) for r in reasons):
        return ",".join(reasons)
    raise PluginBug(f"{origin}: {what} is {type(reasons).__name__}; expected a list of str")


def _extra_columns(scorers: Iterable[Scorer]) -> dict[str, str]:
    """The scorers' own columns; two scorers may share a column only with the same dtype."""
    columns: dict[str, str] = {}
    owner: dict[str, str] = {}
    for scorer in scorers:
        for name, dtype in scorer.columns.items():
            if name in (*SCORER_INPUT, *SCORER_OUTPUT, *META_DTYPES):
                raise BadInput(f"scorer {scorer.name!r}: column {name!r} is one of bpb's own")
            if columns.setdefault(name, dtype) != dtype:
                raise BadInput(
                    f"scorers {owner[name]!r} and {scorer.name!r}: column {name!r} has dtype "
                    f"{columns[name]} in one and {dtype} in the other"
                )
            owner.setdefault(name, scorer.name)
    return columns


class _Columns:
    """Column lists filled row by row, turned into one frame with fixed dtypes."""

    def __init__(self, dtypes: dict[str, str]) -> None:
        self.dtypes = dtypes
        self.data: dict[str, list[Any]] = {name: [] for name in dtypes}

    def repeat(self, values: dict[str, Any], count: int) -> None:
        for name, value in values.items():
            self.data[name].extend([value] * count)

    def extend(self, name: str, values: Sequence[Any]) -> None:
        self.data[name].extend(values)

    def pad(self) -> None:
        """Fill columns that this block of rows did not set (another scorer's) with NaN."""
        rows = max(len(values) for values in self.data.values())
        for values in self.data.values():
            values.extend([float("nan")] * (rows - len(values)))

    def frame(self) -> pd.DataFrame:
        import pandas as pd

        columns = {
            name: pd.Series(values, dtype=self.dtypes[name]) for name, values in self.data.items()
        }
        return pd.DataFrame(columns)


def _read_one(
    run: RunFolder,
    scorers: dict[str, Scorer],
    origins: dict[str, str],
    tasks: dict[str, tuple[Task, str] | None],
    units: _Columns,
    calls: _Columns,
) -> None:
    for key in run.scene_keys:
        scene, truth = run.truth(key)
        meta = {**run.meta, "horizon": key.horizon, "index": key.index}
        meta |= {"scene_id": key.scene_id, "stable": truth.stable}
        meta["unstable_reasons"] = _reasons(truth, run)
        for task, epoch in [(t, e) for e in range(1, run.epochs + 1) for t in run.tasks]:
            meta["epoch"] = epoch
            record = _placed(run, key, task, epoch)
            _check_answer(run, key, epoch, record, tasks[task], scene)
            status = "missing" if record is None else record.status
            answer = None if record is None else record.answer
            scorer = scorers[task]
            rows: list[UnitRow] = unit_rows(scorer, origins[task], answer, truth, scene)
            units.repeat({**meta, "task": task, "scene_rule": scorer.scene_rule}, len(rows))
            units.repeat({"status": status, "correct": False}, len(rows))
            for position, name in enumerate(("unit", "truth", "pred", "duplicate")):
                units.extend(name, [row[position] for row in rows])
            for position, name in enumerate(scorer.columns):
                units.extend(name, [row.values[position] for row in rows])
            units.extend("distance", [float("nan")] * len(rows))
            units.pad()
            _add_call(calls, {**meta, "task": task}, status, record)


def _placed(run: RunFolder, key: SceneKey, task: str, epoch: int) -> AnswerRecord | None:
    """The answer file of (scene, task, epoch), checked to say it is that answer: a file copied
    in from another scene, task, epoch or run would be scored against this scene's truth, and
    an ``ok`` without an answer (bpb writes none) would be scored wrong as if answered.

    Raises:
        BadInput: The file names another scene, task, epoch or adapter, or says ``ok`` with no
            answer (names the file).
    """
    path = answer_path(run.path, key, task, epoch)
    record = read_answer(path)
    if record is None:
        return None
    if record.status == "ok" and record.answer is None:
        raise BadInput(f"{path}: status is 'ok' but answer is null: an ok answer file holds one")
    wanted: dict[str, object] = {"scene_id": key.scene_id, "task": task, "epoch": epoch}
    if isinstance(run.manifest.get("adapter"), str):
        wanted["adapter"] = run.adapter  # as read: a lone surrogate as U+FFFD
    for name, value in wanted.items():
        if getattr(record, name) != value:
            raise BadInput(
                f"{path}: {name} is {getattr(record, name)!r}, but a file here holds the answer of "
                f"{key.scene_id}, task {task}, epoch {epoch} by {run.adapter} (copied in from "
                "another scene, task or run?)"
            )
    return record


def _check_answer(
    run: RunFolder,
    key: SceneKey,
    epoch: int,
    record: AnswerRecord | None,
    task: tuple[Task, str] | None,
    scene: Any,
) -> None:
    """Refuse an ``ok`` answer its task's parser does not accept (a wrong-typed field, a label
    that is none): bpb records only answers the parser validated, a reply it could not parse as
    ``parse_error``; scored, a damaged file would read as the model's wrong answer.

    Raises:
        BadInput: Naming the file and the field at fault; ``PluginBug`` if the parser raised.
    """
    if record is None or record.status != "ok" or record.answer is None or task is None:
        return
    try:
        parsed_answer(task[0], task[1], json.dumps(record.answer), scene, PromptOptions())
    except ParseFailure as exc:
        path = answer_path(run.path, key, record.task, epoch)
        raise BadInput(
            f"{path}: answer: {exc} (a damaged answer file: bpb records only answers the task's "
            "parser accepted)"
        ) from None


def _add_call(
    calls: _Columns, meta: dict[str, Any], status: str, record: AnswerRecord | None
) -> None:
    if record is None:
        values: dict[str, Any] = {**meta, "status": status, "attempts": 0, "retries": 0}
        values |= {name: 0 for name in _USAGE} | {"cost": float("nan"), "latency": float("nan")}
        values |= {"cot": None, "finish_reason": None, "rule": None, "input_mode": None}
        calls.repeat({**values, "error": None, "metadata": None}, 1)
        return
    usage = record.usage
    values = {
        **meta,
        "status": status,
        "attempts": record.attempts,
        "retries": max(record.attempts - 1, 0),
        **{name: int(getattr(usage, name)) for name in _USAGE},
        "cost": float(record.cost) if record.cost is not None else float("nan"),
        "latency": float(record.latency or float("nan")),
        "cot": record.cot,
        "finish_reason": record.finish_reason,
        "rule": record.rule,
        "input_mode": record.input_mode,
        "error": record.error,
        "metadata": json.dumps(record.metadata, sort_keys=True) if record.metadata else None,
    }
    calls.repeat(values, 1)


def _score(
    frame: pd.DataFrame, scorers: dict[str, Scorer], origins: dict[str, str]
) -> pd.DataFrame:
    for task, scorer in scorers.items():
        mask = (frame["task"] == task).to_numpy(dtype=bool)
        if not mask.any():
            continue
        scored = scored_units(
            scorer, origins[task], frame.loc[mask, [*SCORER_INPUT, *scorer.columns]]
        )
        frame.loc[mask, "correct"] = scored["correct"].to_numpy(dtype=bool)
        frame.loc[mask, "distance"] = scored["distance"].to_numpy(dtype=float)
    return frame
