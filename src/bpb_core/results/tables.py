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

Completeness per (run, task, horizon) cell: a cell is the scenes a run was asked about for one
task at one horizon; its completeness is the share of them that got an answer (not
``api_error``, not ``missing``). A score made of too few answers is a statement about missing
data, not about the model: a run stopped by ``--max-cost`` after the first horizons would
otherwise "fall with horizon". So:

- a cell under 100% is *partial*: shown, and marked;
- a cell under ``min_complete`` (default :data:`DEFAULT_MIN_COMPLETE`) is *short*: greyed in
  charts, and a task with a short cell is left out of the leaderboards (its score and every
  suite built on it become NaN), unless the caller asks to include incomplete runs.

Beside them: tokens, cost and latency per run (:func:`usage`), the adapters' own measurements
per run and horizon (:func:`metadata_table`) and the warning lines a table of scores is to be
read with (:func:`warning_lines`).
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

from bpb_core.run_folder import NO_ANSWER, REPLIED

if TYPE_CHECKING:
    from bpb_core.registry import SuiteInfo
    from bpb_core.results.frames import Results


DEFAULT_MIN_COMPLETE = 0.9
"""The share of a cell's scenes that must be answered for it to count in leaderboards."""

Level = Literal["full", "partial", "short"]


def level(completeness: float, min_complete: float) -> Level:
    """``full`` (every scene answered), ``partial`` (some missing) or ``short`` (under
    ``min_complete``: not to be read as a finding)."""
    if completeness >= 1.0:
        return "full"
    return "partial" if completeness >= min_complete else "short"


def cell_levels(acc: pd.DataFrame, min_complete: float) -> pd.Series:
    """The :func:`level` of every row of an accuracy frame (column ``completeness``)."""
    values = acc["completeness"].fillna(0.0).to_numpy(dtype=float)
    return pd.Series([level(v, min_complete) for v in values], index=acc.index, dtype="str")


def worst_cells(acc: pd.DataFrame) -> pd.DataFrame:
    """The least complete cell per (run, task): one row per run, one column per task."""
    worst = acc.pivot_table(
        index="run", columns="task", values="completeness", aggfunc="min", observed=True
    )
    worst.columns.name = None
    return worst


def excluded_tasks(acc: pd.DataFrame, min_complete: float) -> dict[str, list[str]]:
    """Per run, the tasks with a cell under ``min_complete`` (empty lists left out)."""
    short = worst_cells(acc) < min_complete
    return {
        str(run): [str(t) for t in row.index[row]] for run, row in short.iterrows() if row.any()
    }


REJECTED = ("RequestRejected:",)
"""How the error of a call the API refused (a 4xx other than a rate limit) begins: re-running
sends the same request again, so it is not counted with infrastructure failures."""
SETUP = ("SetupFailure:", "AuthenticationFailed:")
"""How the error of a call that stopped its adapter begins (an unknown model, a refused key, an
unreachable provider): a setting to fix before the re-run, not an infrastructure failure."""


def incomplete_lines(results: Results) -> dict[str, str]:
    """Per run with unanswered calls, what to say: how many stopped their adapter (an
    ``api_error`` whose error is one of :data:`SETUP`), failed on infrastructure
    (``api_error``), were refused by the API (one of :data:`REJECTED`) or were never sent
    (``missing``), and that re-running resumes them; for a run still running when it was read,
    that its calls are not answered yet."""
    calls = results.calls
    counts = calls.assign(status=_failures(calls)).groupby(["run", "status"], observed=True).size()
    live = {run.label: run.live for run in results.runs if run.live is not None}
    people = {r.label: _person(calls[calls["run"] == r.label]) for r in results.runs if r.person}
    out: dict[str, str] = {}
    for run, row in counts.unstack(fill_value=0).iterrows():
        failed = int(row.get("api_error", 0))
        rejected = int(row.get("rejected", 0))
        unsent = int(row.get("missing", 0))
        setup = int(row.get("setup", 0))
        waiting = failed + rejected + unsent + setup
        if str(run) in people and waiting:  # a person's session: scenes, not calls
            out[str(run)] = people[str(run)]
            continue
        if str(run) in live and waiting:
            out[str(run)] = (
                f"still running (bpb run pid {live[str(run)]}): "
                f"{_calls(waiting)} not answered yet; report again when it ends"
            )
            continue
        parts = [f"{_calls(setup)} stopped by a setup error (fix it first)"] if setup else []
        parts += [f"{_calls(failed)} failed on infrastructure"] if failed else []
        parts += [f"{_calls(unsent)} never sent"] if unsent else []
        line = f"{' and '.join(parts)}, re-run to resume" if parts else ""
        if rejected:
            refusal = (
                f"{_calls(rejected)} refused by the API (a 4xx: re-running sends the same "
                "request; the error is in each answer file)"
            )
            line = f"{line}; {refusal}" if line else refusal
        if line:
            out[str(run)] = f"incomplete: {line}"
    return out


def _person(calls: pd.DataFrame) -> str:
    """A person's session (``bpb human``) in people's terms: scenes answered of those asked and
    the median time a scene took (its slowest task's: each task's time runs from the page being
    shown to the task's last edit)."""
    scenes = calls.groupby("scene_id", observed=True)
    answered = scenes["status"].agg(lambda s: bool(s.isin(REPLIED).all()))
    seconds = calls[calls["status"].isin(REPLIED)].groupby("scene_id", observed=True)["latency"]
    per_scene = seconds.max().dropna()
    took = f", {per_scene.median():.0f} s per scene (median)" if len(per_scene) else ""
    done, total = int(answered.sum()), len(answered)
    return f"a person's session: {done} of {total} scenes answered{took}; bpb human again resumes"


def _failures(calls: pd.DataFrame) -> pd.Series:
    """Each call's status, an ``api_error`` told apart as ``rejected`` or ``setup`` by how its
    error begins."""
    status = calls["status"].astype(str)
    said = calls["error"].fillna("").astype(str)
    for kind, starts in (("rejected", REJECTED), ("setup", SETUP)):
        status = status.where(~((status == "api_error") & said.str.startswith(starts)), kind)
    return status


UNPARSED_SHARE = 0.5
"""The share of a task's answers that parse errors must reach for the report to say so."""


def unparsed_lines(results: Results) -> dict[str, str]:
    """Per run with a task where at least :data:`UNPARSED_SHARE` of the answers are parse
    errors, what to say: such a score (parse errors count as wrong) tells how the run answered,
    not what it knows, and a run whose every answer failed to parse still reads complete."""
    calls = results.calls[results.calls["status"].isin(["ok", "parse_error"])]
    failed = calls["status"].astype(str) == "parse_error"
    grouped = calls.assign(failed=failed).groupby(["run", "task"], observed=True)["failed"]
    counts = grouped.agg(["sum", "size"]).reset_index()
    out: dict[str, str] = {}
    for run, task, bad, size in counts[["run", "task", "sum", "size"]].itertuples(index=False):
        if bad and bad >= UNPARSED_SHARE * size:
            told = f"{task} {int(bad)} of {int(size)}"
            out[str(run)] = f"{out[str(run)]}, {told}" if str(run) in out else told
    return {
        run: f"answers that could not be parsed ({told}) are scored wrong: those scores say "
        "how the run answered, not what it knows; see the failure gallery"
        for run, told in out.items()
    }


def unanswered_lines(results: Results) -> dict[str, str]:
    """Per run with replies that held no answer (refused by the model or its safety filter,
    cut at the token cap, empty), what to say: how many per task, that they count as wrong in
    the strict score, and for a cut the cap that cut it (a setting of the run, not the model's
    knowledge)."""
    calls = results.calls[results.calls["status"].astype(str).isin(NO_ANSWER)]
    out: dict[str, str] = {}
    for run, frame in calls.groupby("run", observed=True):
        counts = frame.groupby(["task", "status"], observed=True).size()
        told = "; ".join(
            f"{task} " + ", ".join(f"{kind} {n}" for kind, n in by_kind.items() if n)
            for task, by_kind in counts.unstack(fill_value=0).iterrows()
        )
        line = f"replies with no answer, scored wrong ({told})"
        cut = frame["error"][frame["status"].astype(str) == "cut"].dropna()
        out[str(run)] = f"{line}; {cut.iloc[0]}" if len(cut) else line
    return out


def warning_lines(results: Results) -> list[tuple[str, str]]:
    """Every ``(run, line)`` a table of scores is to be read with: calls unanswered
    (:func:`incomplete_lines`), replies that held no answer (:func:`unanswered_lines`), tasks
    mostly unparsed (:func:`unparsed_lines`)."""
    return [
        *incomplete_lines(results).items(),
        *unanswered_lines(results).items(),
        *unparsed_lines(results).items(),
    ]


def _calls(count: int) -> str:
    return f"{count} call" if count == 1 else f"{count} calls"


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
    instead of being read as a finding (see the module docstring). ``worst_cell``
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
    if options.get("scenes") is None:  # computed once for all of them
        options["scenes"] = scene_scores(units)
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
