"""The Q1 scorer: per-ball accuracy over the object balls (rules in
:mod:`bpb_tasks.questions.labels`)."""

from __future__ import annotations

from typing import Literal

from bpb_tasks.billiards.truth import FinalState
from bpb_tasks.questions.ids import ball_id
from bpb_tasks.questions.labels import LabelScorer


class Q1Scorer(LabelScorer):
    """One unit per object ball; a scene scores the share of its balls that are right."""

    name = "q1"
    task = "q1"
    scene_rule: Literal["mean", "all"] = "mean"
    key = "id"
    noun = "ball "
    parse_key = staticmethod(ball_id)

    def labels(self, truth: FinalState) -> dict[str, str]:
        return {str(t.id): t.answer for t in truth.q1}
