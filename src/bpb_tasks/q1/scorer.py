"""The Q1 scorer: per-ball accuracy over the object balls (rules in
:mod:`bpb_tasks.questions.labels`), the metrics reports show beside it, and the confusion
diagnostic.

Most object balls are not touched by the cue ball, so per-ball accuracy rewards answering ``F``
for every ball: the do-nothing ``stasis`` baseline gets about 90% on the paper's setting. The
metrics beside it are not dominated by the ``F`` class:

- ``exact_set``: share of scenes with every object ball right (the set of balls hit);
- ``recall``, ``precision``, ``f1``: of contacts (positive = ``T``), pooled over answered units;
- ``balanced_accuracy``: mean of recall and specificity. It is the chance-corrected one: any
  answer that ignores the scene (always ``F``, always ``T``, coin flips) scores 50% in
  expectation, whatever the share of contacts.

Scene metrics (``per_ball``, ``exact_set``) are means over scenes per horizon, then over
horizons, like the leaderboard; label metrics pool the labelled units (``ok`` answers with a
valid, unduplicated ``T``/``F``) over all horizons.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pandas as pd

from bpb_core.results.tables import RUN_COLUMNS
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.questions.answers import ball_id
from bpb_tasks.questions.labels import ConfusionDiagnostic, LabelScorer, labelled, outcomes, rates

METRIC_NOTES: dict[str, str] = {
    "per_ball": "the paper's metric: share of object balls labelled right; favours 'no "
    "collision', since most balls are not hit (stasis, all F, scores high)",
    "exact_set": "share of scenes with every object ball right (the whole set of balls hit)",
    "recall": "share of true contacts labelled T (stasis: 0%)",
    "precision": "share of T labels that are true contacts",
    "f1": "harmonic mean of precision and recall (0% for an answer that never says T)",
    "balanced_accuracy": "mean of recall and specificity; chance-corrected: any answer that "
    "ignores the scene scores 50%",
}
COUNTS = ("tp", "fp", "fn", "tn")


class Q1Scorer(LabelScorer):
    """One unit per object ball; a scene scores the share of its balls that are right."""

    name = "q1"
    task = "q1"
    scene_rule: Literal["mean", "all"] = "mean"
    key = "id"
    noun = "ball "
    parse_key = staticmethod(ball_id)
    metric_notes = METRIC_NOTES

    def task_metrics(self, units: pd.DataFrame) -> pd.DataFrame:
        """Per-ball and exact-set accuracy, recall, precision, F1, balanced accuracy per run."""
        return q1_metrics(units)

    def labels(self, truth: FinalState) -> dict[str, str]:
        return {str(t.id): t.answer for t in truth.q1}


class Q1Confusion(ConfusionDiagnostic):
    """Q1 confusion over all object balls: tp, fp, fn, tn, precision, recall, F1 per run."""

    name = "q1_confusion"
    title = "Q1 confusion (all object balls; answered units)"
    task = "q1"


def q1_metrics(units: pd.DataFrame) -> pd.DataFrame:
    """Every Q1 metric per run of ``units`` (Q1 units of answered calls), run columns first,
    then :data:`METRIC_NOTES`' columns, then the confusion counts: ``per_ball`` and
    ``exact_set`` are means over scenes then over horizons, the confusion counts, recall,
    precision, F1 and balanced accuracy pool the labelled units."""
    if units.empty:
        return pd.DataFrame(columns=[*RUN_COLUMNS, *METRIC_NOTES, *COUNTS])
    grouped = units.groupby([*RUN_COLUMNS, "horizon", "index"], observed=True)["correct"]
    scenes = pd.DataFrame({"per_ball": grouped.mean(), "exact_set": grouped.all()})
    scenes = scenes.astype("float64").reset_index()
    columns = ["per_ball", "exact_set"]
    by_horizon = scenes.groupby([*RUN_COLUMNS, "horizon"], observed=True)[columns].mean()
    frame = labelled(units, ("q1",))
    counts = pd.concat([frame[RUN_COLUMNS], outcomes(frame)], axis=1)
    out = rates(counts.groupby(RUN_COLUMNS, observed=True)[list(COUNTS)].sum())
    tp, wrong = out["tp"], out["fp"] + out["fn"]
    out["f1"] = (2 * tp / (2 * tp + wrong).where(2 * tp + wrong > 0)).astype("float64")
    negatives = (out["tn"] + out["fp"]).where(out["tn"] + out["fp"] > 0)
    specificity = out["tn"] / negatives
    out["balanced_accuracy"] = (out["recall"] + specificity) / 2
    both = by_horizon.groupby(level=RUN_COLUMNS, observed=True)[columns].mean()
    both = both.join(out, how="left")
    both[list(COUNTS)] = both[list(COUNTS)].fillna(0).astype("int64")
    both = both.reset_index()[[*RUN_COLUMNS, *METRIC_NOTES, *COUNTS]]
    return both.astype({name: np.float64 for name in METRIC_NOTES})
