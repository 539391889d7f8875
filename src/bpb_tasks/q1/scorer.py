"""The Q1 scorer: per-ball accuracy over the object balls (rules in
:mod:`bpb_tasks.questions.labels`), with the metrics reports show beside it
(:mod:`bpb_tasks.q1.metrics`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

from bpb_tasks.billiards.truth import FinalState
from bpb_tasks.q1.metrics import METRIC_NOTES, q1_metrics
from bpb_tasks.questions.ids import ball_id
from bpb_tasks.questions.labels import LabelScorer

if TYPE_CHECKING:
    import pandas as pd


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
        """Per-ball and exact-set accuracy, recall, precision, F1, balanced accuracy per run
        (:mod:`bpb_tasks.q1.metrics`)."""
        return q1_metrics(units)

    def labels(self, truth: FinalState) -> dict[str, str]:
        return {str(t.id): t.answer for t in truth.q1}
