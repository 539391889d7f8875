"""Accuracy tables and leaderboards derived from the units frame of :mod:`bpb_core.results`.

Two views (SPEC section 8):

- ``strict`` (the paper): every expected scene counts; a missing answer, an API error or a parse
  error is wrong.
- ``answered``: scenes whose call never produced an answer (``api_error``, ``missing``) are left
  out; a parse error is still wrong. ``completeness`` says what share of scenes is left.

A scene's score for a task is the share of its units that are right (``mean``: Q1, Q3) or 1 when
all are right (``all``: Q2). A task's accuracy at a horizon is the mean over scenes; the
leaderboard score is the mean over horizons; ``total`` = 0.3 Q1 + 0.3 Q2 + 0.4 Q3.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pandas as pd

View = Literal["strict", "answered"]
VIEWS: tuple[View, ...] = ("strict", "answered")
UNANSWERED = ("api_error", "missing")
TOTAL_WEIGHTS: dict[str, float] = {"q1": 0.3, "q2": 0.3, "q3": 0.4}
METRICS = ("q1", "q2", "q3", "total")
RUN_COLUMNS = ["run", "adapter", "model", "baseline"]
SCENE_KEYS = ["run", "task", "horizon", "index", "scene_id"]


def scene_scores(units: pd.DataFrame, *, stable_only: bool = False) -> pd.DataFrame:
    """One row per (run, task, scene): ``score`` in [0, 1], ``status``, ``stable``, run columns."""
    frame = units[units["stable"].fillna(False).astype(bool)] if stable_only else units
    keys = [*SCENE_KEYS, "scene_rule"]
    grouped = frame.groupby(keys, observed=True, sort=False)
    scores = grouped["correct"].agg(["mean", "min"])
    first = grouped[["status", "stable", "adapter", "model", "baseline"]].first()
    out = pd.concat([scores, first], axis=1).reset_index()
    is_all = (out["scene_rule"] == "all").to_numpy(dtype=bool)
    score = np.where(is_all, out["min"].astype(float), out["mean"].astype(float))
    out["score"] = score.astype("float64")
    return out.drop(columns=["mean", "min", "scene_rule"])


def _in_view(scenes: pd.DataFrame, view: View) -> pd.DataFrame:
    if view == "strict":
        return scenes
    if view == "answered":
        return scenes[~scenes["status"].isin(UNANSWERED)]
    raise ValueError(f"view must be 'strict' or 'answered', not {view!r}")


def accuracy(
    units: pd.DataFrame, *, view: View = "strict", stable_only: bool = False
) -> pd.DataFrame:
    """Accuracy per run, task and horizon, with scene counts and completeness.

    Returns:
        Columns ``run, adapter, model, baseline, task, horizon, accuracy, scenes, answered,
        expected, completeness`` (``scenes`` counted in the view; ``answered`` = not
        api_error/missing; ``expected`` = all scenes the run should have answered).
    """
    scenes = scene_scores(units, stable_only=stable_only)
    scenes["answered"] = ~scenes["status"].isin(UNANSWERED)
    keys = [*RUN_COLUMNS, "task", "horizon"]
    counts = scenes.groupby(keys, observed=True).agg(
        expected=("score", "size"), answered=("answered", "sum")
    )
    kept = _in_view(scenes, view)
    acc = kept.groupby(keys, observed=True).agg(
        accuracy=("score", "mean"), scenes=("score", "size")
    )
    out = counts.join(acc, how="left").reset_index()
    out["completeness"] = out["answered"] / out["expected"]
    out["scenes"] = out["scenes"].fillna(0).astype("int64")
    out["answered"] = out["answered"].astype("int64")
    cols = [*keys, "accuracy", "scenes", "answered", "expected", "completeness"]
    return out[cols].sort_values(["run", "task", "horizon"]).reset_index(drop=True)


def by_horizon(
    units: pd.DataFrame, *, view: View = "strict", stable_only: bool = False
) -> pd.DataFrame:
    """Wide table: one row per (run, task), one column per horizon, and ``mean`` over horizons."""
    acc = accuracy(units, view=view, stable_only=stable_only)
    wide = acc.pivot_table(
        index=["run", "baseline", "task"], columns="horizon", values="accuracy", observed=True
    )
    wide.columns = [f"h{h:g}" for h in wide.columns]
    wide["mean"] = wide.mean(axis=1)
    return wide.reset_index()


def leaderboard(
    units: pd.DataFrame,
    *,
    view: View = "strict",
    stable_only: bool = False,
    sort_by: str = "total",
) -> pd.DataFrame:
    """One row per run: Q1, Q2, Q3 (means over horizons), total, completeness; best first.

    ``total`` is NaN for a run that lacks one of the three tasks.
    """
    acc = accuracy(units, view=view, stable_only=stable_only)
    means = acc.pivot_table(
        index=RUN_COLUMNS, columns="task", values="accuracy", aggfunc="mean", observed=True
    )
    for task in TOTAL_WEIGHTS:
        if task not in means.columns:
            means[task] = np.nan
    means["total"] = sum(w * means[t] for t, w in TOTAL_WEIGHTS.items())
    counts = acc.groupby(RUN_COLUMNS, observed=True)[["answered", "expected"]].sum()
    out = means.join(counts).reset_index()
    out.columns.name = None
    out["completeness"] = out["answered"] / out["expected"]
    fixed = (*RUN_COLUMNS, *METRICS, "answered", "expected", "completeness")
    other = [c for c in out.columns if c not in fixed]  # tasks beyond q1-q3
    out = out[[*RUN_COLUMNS, *METRICS, *other, "completeness", "expected"]]
    return out.sort_values(sort_by, ascending=False, na_position="last").reset_index(drop=True)


def summary(units: pd.DataFrame) -> pd.DataFrame:
    """Strict leaderboard plus the answered-only total and the completeness, best first.

    Columns: ``run, adapter, model, baseline, q1, q2, q3, total, total_answered,
    completeness, expected`` (``expected``: scene-task pairs the run should have answered).
    """
    strict = leaderboard(units, view="strict")
    answered = leaderboard(units, view="answered").set_index("run")["total"]
    position = list(strict.columns).index("total") + 1
    strict.insert(position, "total_answered", strict["run"].map(answered))
    return strict


def summary_records(units: pd.DataFrame) -> list[dict[str, object]]:
    """:func:`summary` as JSON-ready dicts (NaN becomes ``None``)."""
    table = summary(units)
    records: list[dict[str, object]] = []
    for row in table.to_dict(orient="records"):
        records.append({str(k): _plain(v) for k, v in row.items()})
    return records


def _plain(value: object) -> object:
    if isinstance(value, (np.floating, float)):
        return None if np.isnan(value) else float(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value
