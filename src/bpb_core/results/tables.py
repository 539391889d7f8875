"""Accuracy tables and leaderboards derived from the units frame of :mod:`bpb_core.results`.

Two views (SPEC section 8):

- ``strict`` (the paper): every expected scene counts; a missing answer, an API error or a parse
  error is wrong.
- ``answered``: scenes whose call never produced an answer (``api_error``, ``missing``) are left
  out; a parse error is still wrong. ``completeness`` says what share of scenes is left.

A scene's score for a task is the share of its units that are right (``mean``) or 1 when all
are right (``all``), as the task's scorer says. A task's accuracy at a horizon is the mean over
scenes; the leaderboard score is the mean over horizons; a suite's score is the weighted sum of
its tasks' leaderboard scores (NaN for a run that lacks one of them).

Beside them: tokens, cost and latency per run (:func:`usage`) and the adapters' own
measurements per run and horizon (:func:`metadata_table`).
"""

from __future__ import annotations

import json
import math
import statistics
from collections import defaultdict
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pandas as pd

from bpb_core.results.completeness import DEFAULT_MIN_COMPLETE, excluded_tasks
from bpb_core.run_folder import REPLIED

if TYPE_CHECKING:
    from bpb_core.registry import SuiteInfo

View = Literal["strict", "answered"]
UNANSWERED = ("api_error", "missing")
RUN_COLUMNS = ["run", "adapter", "model", "baseline"]
SCENE_KEYS = ["run", "task", "horizon", "index", "scene_id", "epoch"]


def scene_scores(units: pd.DataFrame) -> pd.DataFrame:
    """One row per (run, task, scene): ``score`` in [0, 1], ``status``, ``stable``, run columns.

    Every table below starts from them; a caller deriving several tables from one units frame
    computes them once and passes them as ``scenes`` (:attr:`Results.scenes
    <bpb_core.results.frames.Results.scenes>`), never modifying them."""
    keys = [*SCENE_KEYS, "scene_rule"]
    grouped = units.groupby(keys, observed=True, sort=False)
    scores = grouped["correct"].agg(["mean", "min"])
    first = grouped[["status", "stable", "adapter", "model", "baseline"]].first()
    out = pd.concat([scores, first], axis=1).reset_index()
    is_all = (out["scene_rule"] == "all").to_numpy(dtype=bool)
    score = np.where(is_all, out["min"].astype(float), out["mean"].astype(float))
    out["score"] = score.astype("float64")
    return out.drop(columns=["mean", "min", "scene_rule"])


def stable_exclusions(units: pd.DataFrame) -> pd.DataFrame:
    """Scenes left out of the stable subset, per reason: one row per reason named by the ground
    truths (a scene may count under several), then ``any`` (all unstable scenes) and
    ``not annotated``. Columns ``reason`` and ``scenes`` (distinct scene ids)."""
    scenes = units.drop_duplicates("scene_id")[["stable", "unstable_reasons"]]
    unstable = scenes[scenes["stable"].fillna(True).eq(False)]
    reasons = unstable["unstable_reasons"].fillna("").astype(str).str.split(",").explode()
    counts = reasons[reasons != ""].value_counts()
    rows = [*sorted((str(k), int(v)) for k, v in counts.items()), ("any", len(unstable))]
    rows.append(("not annotated", int(scenes["stable"].isna().sum())))
    return pd.DataFrame(rows, columns=["reason", "scenes"])


def _in_view(scenes: pd.DataFrame, view: View) -> pd.DataFrame:
    if view == "strict":
        return scenes
    if view == "answered":
        return scenes[~scenes["status"].isin(UNANSWERED)]
    raise ValueError(f"view must be 'strict' or 'answered', not {view!r}")


def accuracy(
    units: pd.DataFrame,
    *,
    view: View = "strict",
    stable_only: bool = False,
    scenes: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """Accuracy per run, task and horizon, with scene counts and completeness.

    Returns:
        Columns ``run, adapter, model, baseline, task, horizon, accuracy, scenes, answered,
        expected, completeness, epochs``: ``scenes`` counts the scene-tasks in the view, each
        once; ``answered`` (not api_error/missing) and ``expected`` count answers, ``epochs``
        per scene-task (``--epochs``), so ``completeness`` is the share of answers given.
    """
    scenes = scene_scores(units) if scenes is None else scenes
    if stable_only:
        scenes = scenes[scenes["stable"].fillna(False).astype(bool)]
    scenes = scenes.assign(answered=~scenes["status"].isin(UNANSWERED))
    keys = [*RUN_COLUMNS, "task", "horizon"]
    counts = scenes.groupby(keys, observed=True).agg(
        expected=("score", "size"), answered=("answered", "sum"), epochs=("epoch", "max")
    )
    kept = _in_view(scenes, view)
    acc = kept.groupby(keys, observed=True).agg(
        accuracy=("score", "mean"), scenes=("scene_id", "nunique")
    )
    out = counts.join(acc, how="left").reset_index()
    out["completeness"] = out["answered"] / out["expected"]
    out["scenes"] = out["scenes"].fillna(0).astype("int64")
    out["answered"] = out["answered"].astype("int64")
    out["epochs"] = out["epochs"].astype("int64")
    cols = [*keys, "accuracy", "scenes", "answered", "expected", "completeness", "epochs"]
    return out[cols].sort_values(["run", "task", "horizon"]).reset_index(drop=True)


def by_horizon(
    units: pd.DataFrame,
    *,
    view: View = "strict",
    stable_only: bool = False,
    min_complete: float = DEFAULT_MIN_COMPLETE,
    include_incomplete: bool = False,
    scenes: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """Wide table: one row per (run, task), one column per horizon, ``mean`` over horizons,
    then each horizon's completeness (``h1_complete``, ...). ``mean`` is NaN when a cell is
    under ``min_complete`` answered, unless ``include_incomplete``."""
    acc = accuracy(units, view=view, stable_only=stable_only, scenes=scenes)
    keys = ["run", "baseline", "task"]
    cells = acc.assign(run=acc["run"].astype(str)).set_index([*keys, "horizon"])
    wide = cells["accuracy"].unstack("horizon")  # keeps cells with no answer (NaN)
    done = cells["completeness"].unstack("horizon")
    labels = [f"h{h:g}" for h in wide.columns]
    wide.columns, done.columns = labels, [f"{h}_complete" for h in labels]
    wide["mean"] = wide.mean(axis=1)
    if not include_incomplete:
        wide.loc[(done < min_complete).any(axis=1), "mean"] = np.nan
    return wide.join(done).reset_index()


def tasks_of(units: pd.DataFrame) -> list[str]:
    """Tasks present in a units frame, sorted."""
    return sorted(str(t) for t in units["task"].unique())


def suite_score(means: pd.DataFrame, suite: SuiteInfo) -> pd.Series:
    """A suite's score per row of ``means`` (one column per task; NaN when a task is absent)."""
    total = pd.Series(0.0, index=means.index)
    for task, weight in suite.weights.items():
        column = means[task] if task in means.columns else pd.Series(np.nan, index=means.index)
        total = total + weight * column
    return total


def metrics(units: pd.DataFrame, suites: Sequence[SuiteInfo] = ()) -> list[str]:
    """The leaderboard's score columns: every task present, then every suite."""
    return [*tasks_of(units), *(s.name for s in suites)]


def leaderboard(
    units: pd.DataFrame,
    suites: Sequence[SuiteInfo] = (),
    *,
    view: View = "strict",
    stable_only: bool = False,
    sort_by: str | None = None,
    min_complete: float = DEFAULT_MIN_COMPLETE,
    include_incomplete: bool = False,
    scenes: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """One row per run: each task's score (mean over horizons), each suite's weighted total,
    completeness; best first (by ``sort_by``, default the first suite, else the mean task).

    A task with a (task, horizon) cell less than ``min_complete`` answered scores NaN (and so
    does every suite built on it), unless ``include_incomplete``: it is left out of the ranking
    instead of being read as a finding (:mod:`bpb_core.results.completeness`). ``worst_cell``
    is the run's least complete cell; ``short`` names its tasks with a cell under
    ``min_complete``. ``expected`` counts the scene-tasks the run was asked, each once;
    ``epochs`` is how many times each was asked (``--epochs``; completeness counts answers).
    """
    acc = accuracy(units, view=view, stable_only=stable_only, scenes=scenes)
    tasks = tasks_of(units)
    means = acc.pivot_table(
        index=RUN_COLUMNS, columns="task", values="accuracy", aggfunc="mean", observed=True
    ).reindex(columns=tasks)
    short = excluded_tasks(acc, min_complete)
    if not include_incomplete:
        for run, names in short.items():
            means.loc[means.index.get_level_values("run") == run, names] = np.nan
    for suite in suites:
        means[suite.name] = suite_score(means, suite)
    cells = acc.assign(scene_tasks=acc["expected"] // acc["epochs"])
    counts = cells.groupby(RUN_COLUMNS, observed=True).agg(
        answered=("answered", "sum"), answers=("expected", "sum"),
        expected=("scene_tasks", "sum"), epochs=("epochs", "max"),
    )  # fmt: skip
    out = means.reindex(counts.index).join(counts).reset_index()  # a run with no answer stays
    out.columns.name = None
    out["completeness"] = out["answered"] / out["answers"]
    out["worst_cell"] = out["run"].map(acc.groupby("run", observed=True)["completeness"].min())
    out["short"] = [", ".join(short.get(str(run), [])) for run in out["run"]]
    columns = [*metrics(units, suites), "completeness", "worst_cell", "short", "expected"]
    columns.append("epochs")
    out = out[[*RUN_COLUMNS, *columns]]
    key = sort_by or (suites[0].name if suites else None)
    order = out[key] if key is not None else out[tasks].mean(axis=1)
    ranked = out.assign(_order=order.to_numpy()).sort_values(
        "_order", ascending=False, na_position="last", kind="stable"
    )
    return ranked.drop(columns="_order").reset_index(drop=True)


def summary(units: pd.DataFrame, suites: Sequence[SuiteInfo] = (), **options: Any) -> pd.DataFrame:
    """Strict leaderboard plus each suite's answered-only score and the completeness, best
    first (``options``: ``min_complete``, ``include_incomplete``, ``scenes`` of
    :func:`leaderboard`).

    Columns: ``run, adapter, model, baseline``, each task and each suite followed by its
    answered-only score ``<name>_answered``, ``completeness, worst_cell, short, expected,
    epochs`` (``expected``: scene-task pairs the run should have answered, each once however
    many ``epochs`` it asked them).
    """
    options.setdefault("scenes", scene_scores(units))
    strict = leaderboard(units, suites, view="strict", **options)
    answered = leaderboard(units, suites, view="answered", **options).set_index("run")
    for name in metrics(units, suites):
        position = list(strict.columns).index(name) + 1
        strict.insert(position, f"{name}_answered", strict["run"].map(answered[name]))
    return strict


def usage(calls: pd.DataFrame) -> pd.DataFrame:
    """Tokens (incl. reasoning), cost, latency, retries and failures per run.

    ``cost`` sums the calls whose cost is known; ``cost_unknown`` counts the others (NaN cost
    is never read as 0). Missing calls (no answer file) are counted, not measured.
    """
    made = calls[calls["status"] != "missing"]
    grouped = made.groupby(RUN_COLUMNS, observed=True)
    out = grouped.agg(
        calls=("status", "size"),
        input_tokens=("input_tokens", "sum"),
        output_tokens=("output_tokens", "sum"),
        reasoning_tokens=("reasoning_tokens", "sum"),
        cached_tokens=("cached_tokens", "sum"),
        cost=("cost", lambda c: c.sum(min_count=1)),
        cost_unknown=("cost", lambda c: int(c.isna().sum())),
        latency_mean=("latency", "mean"),
        latency_median=("latency", "median"),
        retries=("retries", "sum"),
    )
    status = calls.groupby([*RUN_COLUMNS, "status"], observed=True).size().unstack(fill_value=0)
    names = [*REPLIED, "api_error", "missing"]
    out[names] = status.reindex(index=out.index, columns=names, fill_value=0).astype("int64")
    out["tokens_per_call"] = (out["input_tokens"] + out["output_tokens"]) / out["calls"]
    return out.reset_index()


Value = bool | float | str  # one measurement as an answer file holds it (JSON)

METADATA_COLUMNS: dict[str, str] = {
    "run": "str",
    "horizon": "float64",
    "measure": "str",
    "scenes": "int64",
    "median": "float64",
    "mean": "float64",
    "max": "float64",
}


def metadata_table(calls: pd.DataFrame) -> pd.DataFrame:
    """The adapters' own measurements (``calls["metadata"]``): one row per (run, horizon,
    measure); empty (with the columns of :data:`METADATA_COLUMNS`) when no answer carries any.

    Core does not know what a measure means: a numeric one gets its count of scenes, median,
    mean and maximum; a yes/no one (JSON ``true``/``false``) its count and the share true
    (``mean``); a text one (a reason, a label) its count. Each scene counts once, however many
    answers it has (tasks, ``--epochs``), its value the mean over them.
    """
    values: dict[tuple[str, float, str], dict[str, list[Value]]] = defaultdict(
        lambda: defaultdict(list)
    )
    parsed: dict[str, dict[str, Value]] = {}  # the tasks of a scene often carry the same text
    rows = calls.loc[calls["metadata"].notna(), ["run", "horizon", "scene_id", "metadata"]]
    for run, horizon, scene_id, text in rows.itertuples(index=False):
        if text not in parsed:
            parsed[text] = json.loads(text)
        for name, value in parsed[text].items():
            values[(str(run), float(horizon), str(name))][str(scene_id)].append(value)
    records = [_summary(key, by_scene) for key, by_scene in sorted(values.items())]
    frame = pd.DataFrame(records, columns=list(METADATA_COLUMNS))
    return frame.astype(METADATA_COLUMNS)


def _summary(key: tuple[str, float, str], by_scene: dict[str, list[Value]]) -> dict[str, object]:
    """One measure's row: each scene once, its value the mean over its answers."""
    run, horizon, measure = key
    row: dict[str, object] = {"run": run, "horizon": horizon, "measure": measure}
    row["scenes"] = len(by_scene)
    found = [v for answers in by_scene.values() for v in answers]
    numeric = all(isinstance(v, int | float) and math.isfinite(v) for v in found)
    if not numeric:  # a text (or a mix with one): only counted
        return row | {"median": math.nan, "mean": math.nan, "max": math.nan}
    scenes = sorted(statistics.fmean(map(float, answers)) for answers in by_scene.values())
    if all(isinstance(v, bool) for v in found):  # a yes/no: its share, no median
        return row | {"median": math.nan, "mean": statistics.fmean(scenes), "max": math.nan}
    middle, mean = statistics.median(scenes), statistics.fmean(scenes)
    return row | {"median": middle, "mean": mean, "max": scenes[-1]}


def metadata_by_horizon(table: pd.DataFrame) -> pd.DataFrame:
    """:func:`metadata_table` as one row per (run, measure) and one column per horizon
    (``h1``...): the median of a numeric measure, the share of a yes/no one, the count of a text
    one (its ``statistic`` column says which), to read beside the accuracy by horizon."""
    if table.empty:
        return pd.DataFrame(columns=["run", "measure", "statistic"])
    share = table["median"].isna() & table["mean"].notna()
    counted = table["scenes"].astype("float64")
    value = table["median"].where(table["median"].notna(), table["mean"].where(share, counted))
    statistic = pd.Series("count", index=table.index).mask(share, "share")
    frame = table.assign(
        value=value,
        statistic=statistic.mask(table["median"].notna(), "median"),
        column=[f"h{h:g}" for h in table["horizon"]],
    )
    wide = frame.pivot_table(
        index=["run", "measure", "statistic"], columns="column", values="value", sort=False
    )
    order = [f"h{h:g}" for h in sorted(table["horizon"].unique())]
    return wide[order].reset_index().rename_axis(columns=None)
