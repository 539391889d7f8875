"""Published figures beside runs: each score a reference states for a model, next to the score
of every run of that model on the same scenes.

A run's figure is the strict score (an unanswered scene counts as wrong, as a missing answer
does in a published table) with its bootstrap interval, over the reference's horizons for a mean
and over one horizon for a per-horizon figure. A figure the run cannot be compared on (it has no
scenes at a horizon the figure covers) keeps the stated value and says why the run's is blank;
a task the run did not ask gives no row. Rows of runs that answered only part of the scenes say
how much.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from bpb_core.registry import Figure, ReferenceInfo, SuiteInfo, model_key
from bpb_core.results.tables import UNANSWERED, scene_scores, tasks_of
from bpb_core.results.uncertainty import bootstrap_ci

COLUMNS = [
    "run", "reference", "model", "metric", "horizon", "estimate", "lo", "hi", "stated", "diff",
    "where", "note", "source",
]  # fmt: skip


def reference_table(
    units: pd.DataFrame,
    suites: Sequence[SuiteInfo],
    references: Sequence[ReferenceInfo],
    *,
    n_boot: int = 2000,
    seed: int = 0,
    scenes: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """One row per (model run, stated figure of its model): see the module docstring
    (``scenes``: the :func:`~bpb_core.results.tables.scene_scores` of ``units``, if computed).

    Returns:
        Columns :data:`COLUMNS`; ``horizon`` NaN for a mean, ``estimate``/``lo``/``hi``/
        ``diff`` NaN where the run cannot be compared (``note`` says why).
    """
    rows: list[dict[str, Any]] = []
    scenes = scene_scores(units) if scenes is None else scenes
    models = units.loc[~units["baseline"].astype(bool), ["run", "adapter", "model"]]
    for run, adapter, model in models.drop_duplicates().itertuples(index=False):
        keys = {model_key(str(adapter)), model_key(str(model))}
        mine = units[units["run"] == run]
        scored = scenes[scenes["run"] == run]
        tasks = set(tasks_of(mine))
        metrics = tasks | {s.name for s in suites if set(s.weights) <= tasks}
        for reference in references:
            figures = [
                f for f in reference.figures if model_key(f.model) in keys and f.metric in metrics
            ]
            rows += _run_rows(str(run), mine, scored, suites, reference, figures, n_boot, seed)
    return pd.DataFrame(rows, columns=COLUMNS).astype({c: "float64" for c in _NUMBERS})


_NUMBERS = ("horizon", "estimate", "lo", "hi", "stated", "diff")


def _run_rows(
    run: str,
    units: pd.DataFrame,
    scenes: pd.DataFrame,
    suites: Sequence[SuiteInfo],
    reference: ReferenceInfo,
    figures: Sequence[Figure],
    n_boot: int,
    seed: int,
) -> list[dict[str, Any]]:
    """The rows of one run against one reference's figures of its model."""
    have = {round(float(h), 9) for h in units["horizon"].unique().tolist()}
    rows = []
    for span in dict.fromkeys(_span(f, reference) for f in figures):
        missing = sorted(set(span) - have)
        sub = units[units["horizon"].round(9).isin(span)]
        scored = scenes[scenes["horizon"].round(9).isin(span)]
        scores: dict[str, Any] = {}
        if not missing:
            ci = bootstrap_ci(sub, suites, n_boot=n_boot, seed=seed, scenes=scored)
            values = ci[["estimate", "lo", "hi"]].to_numpy(dtype=float).tolist()
            scores = dict(zip(ci["metric"].astype(str), map(tuple, values), strict=True))
        note = _note(missing, scored["status"])
        for figure in (f for f in figures if _span(f, reference) == span):
            rows.append(_row(run, reference, figure, scores.get(figure.metric), note))
    return rows


def _span(figure: Figure, reference: ReferenceInfo) -> tuple[float, ...]:
    """The horizons a figure is over (rounded so that 1 and 1.0000000001 are one horizon)."""
    spans = reference.horizons if figure.horizon is None else (figure.horizon,)
    return tuple(round(float(h), 9) for h in spans)


def _note(missing: Sequence[float], status: pd.Series) -> str:
    """Why a run's figure is blank, or how much of its scenes it answered (``status``: of each
    scene score)."""
    if missing:
        listed = ", ".join(f"{h:g}" for h in missing)
        return f"not comparable: the run has no scenes at horizon {listed} s"
    answered = float((~status.isin(UNANSWERED)).mean()) if len(status) else 0.0
    return "" if answered >= 1 else f"{answered:.0%} answered (unanswered count as wrong)"


def _row(
    run: str,
    reference: ReferenceInfo,
    figure: Figure,
    score: tuple[float, float, float] | None,
    note: str,
) -> dict[str, Any]:
    estimate, lo, hi = score if score is not None else (np.nan, np.nan, np.nan)
    return {
        "run": run,
        "reference": reference.name,
        "model": figure.model,
        "metric": figure.metric,
        "horizon": np.nan if figure.horizon is None else figure.horizon,
        "estimate": estimate,
        "lo": lo,
        "hi": hi,
        "stated": figure.value,
        "diff": estimate - figure.value,
        "where": figure.where,
        "note": note,
        "source": reference.source,
    }
