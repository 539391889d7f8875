"""Completeness per (run, task, horizon) cell, and which scores it leaves standing.

A cell is the scenes a run was asked about for one task at one horizon; its completeness is the
share of them that got an answer (not ``api_error``, not ``missing``). A score made of too few
answers is a statement about missing data, not about the model: a run stopped by ``--max-cost``
after the first horizons would otherwise "fall with horizon". So:

- a cell under 100% is *partial*: shown, and marked;
- a cell under ``min_complete`` (default :data:`DEFAULT_MIN_COMPLETE`) is *short*: greyed in
  charts, and a task with a short cell is left out of the leaderboards (its score and every
  suite built on it become NaN), unless the caller asks to include incomplete runs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import pandas as pd

from bpb_core.run_folder import NO_ANSWER, REPLIED

if TYPE_CHECKING:
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
