"""Run folders to pandas: the one place that builds the results frames.

:func:`load_results` reads run folders (``run.json`` plus ``h{t}/scene_{i}/{task}.json``) and
the dataset each one names, cuts every answer into scored units with the task's scorer, scores
them vectorised and returns two frames with explicit dtypes:

- ``units``: one row per scored unit (object ball, wall, ball position) of every expected
  (run, scene, task); a scene the run has no answer file for appears with status ``missing``.
- ``calls``: one row per (run, scene, task) with status, tokens, cost, latency and retries.

Everything else (accuracies, leaderboards, diagnostics, reports) is derived from these frames by
the ``bpb_core.results_*`` modules. Nothing here prints.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.errors import BadInput
from bpb_core.results.reading import RunFolder, find_runs, read_answer, read_run, read_truth
from bpb_core.units import SCORER_INPUT, SCORER_OUTPUT, UnitRow

if TYPE_CHECKING:
    import pandas as pd

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
    "stable": "boolean",
    "scene_rule": "category",
}
UNIT_DTYPES: dict[str, str] = {**META_DTYPES, **SCORER_INPUT, **SCORER_OUTPUT}
"""Columns of the units frame and their dtypes (``stable`` is NA when not annotated)."""

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
}
"""Columns of the calls frame (``cost`` is NaN when unknown, never a made-up 0)."""

_USAGE = ("input_tokens", "output_tokens", "reasoning_tokens", "cached_tokens")


@dataclass(frozen=True)
class Results:
    """The two frames every table and report is derived from, and the run folders read."""

    units: pd.DataFrame
    calls: pd.DataFrame
    runs: tuple[RunFolder, ...] = ()


def load_results(
    run_dirs: Path | str | Iterable[Path | str], *, registry: Registry | None = None
) -> Results:
    """Read and score run folders.

    Args:
        run_dirs: Run folders (holding ``run.json``) or folders of run folders.
        registry: Where scorers come from; default: all installed plugins.

    Raises:
        BadInput: No run folder found, or a run or answer file cannot be read.
    """
    from bpb_core.registry import make_registry

    runs = find_runs(run_dirs)
    registry = registry if registry is not None else make_registry()
    scorers: dict[str, Any] = {}
    units = _Columns(UNIT_DTYPES)
    calls = _Columns(CALL_DTYPES)
    for run in runs:
        for task in run.tasks:
            if task not in scorers:
                scorers[task] = _scorer_for(registry, task, run)
        _read_one(run, scorers, units, calls)
    unit_frame = _score(units.frame(), scorers)
    return Results(unit_frame, calls.frame(), tuple(runs))


def load_frame(
    run_dirs: Path | str | Iterable[Path | str], *, registry: Registry | None = None
) -> pd.DataFrame:
    """The scored units frame of :func:`load_results` (one row per scored unit)."""
    return load_results(run_dirs, registry=registry).units


def _scorer_for(registry: Registry, task: str, run: RunFolder) -> Any:
    found = registry.scorers_for(task)
    if not found:
        raise BadInput(f"{run.path / 'run.json'}: tasks: no scorer is installed for task {task!r}")
    return registry.scorer(found[0].info.name)


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

    def frame(self) -> pd.DataFrame:
        import pandas as pd

        columns = {
            name: pd.Series(values, dtype=self.dtypes[name]) for name, values in self.data.items()
        }
        return pd.DataFrame(columns)


def _read_one(run: RunFolder, scorers: dict[str, Any], units: _Columns, calls: _Columns) -> None:
    for key in run.scene_keys:
        scene, final = read_truth(run.dataset, key)
        stable = final.stability.stable if final.stability is not None else None
        meta = {**run.meta, "horizon": key.horizon, "index": key.index}
        meta |= {"scene_id": key.scene_id, "stable": stable}
        folder = str(key.dir(run.path))
        for task in run.tasks:
            record = read_answer(folder, task)
            scorer = scorers[task]
            rows: list[UnitRow] = scorer.units(record.get("answer"), final, scene)
            units.repeat({**meta, "task": task, "scene_rule": scorer.scene_rule}, len(rows))
            units.repeat({"status": record["status"], "correct": False}, len(rows))
            for position, name in enumerate(UnitRow._fields):
                units.extend(name, [row[position] for row in rows])
            units.extend("distance", [float("nan")] * len(rows))
            _add_call(calls, {**meta, "task": task}, record)


def _add_call(calls: _Columns, meta: dict[str, Any], record: dict[str, Any]) -> None:
    usage = record.get("usage") or {}
    attempts = int(record.get("attempts") or 0)
    cost = record.get("cost")
    values = {
        **meta,
        "status": record["status"],
        "attempts": attempts,
        "retries": max(attempts - 1, 0),
        **{name: int(usage.get(name) or 0) for name in _USAGE},
        "cost": float(cost) if cost is not None else float("nan"),
        "latency": float(record.get("latency") or float("nan")),
        "cot": record.get("cot"),
    }
    for name in ("finish_reason", "rule", "input_mode", "error"):
        values[name] = record.get(name)
    calls.repeat(values, 1)


def _score(frame: pd.DataFrame, scorers: dict[str, Any]) -> pd.DataFrame:
    for task, scorer in scorers.items():
        mask = (frame["task"] == task).to_numpy(dtype=bool)
        if not mask.any():
            continue
        scored = scorer.score(frame.loc[mask, list(SCORER_INPUT)])
        frame.loc[mask, "correct"] = scored["correct"].to_numpy(dtype=bool)
        frame.loc[mask, "distance"] = scored["distance"].to_numpy(dtype=float)
    return frame


def summary(frame: pd.DataFrame) -> pd.DataFrame:
    """One row per run: the four leaderboard scores (strict), answered-only total, completeness.

    See :func:`bpb_core.results.tables.summary`.
    """
    from bpb_core.results.tables import summary as _summary

    return _summary(frame)


__all__ = [
    "CALL_DTYPES",
    "UNIT_DTYPES",
    "Results",
    "find_runs",
    "load_frame",
    "load_results",
    "read_run",
    "summary",
]
