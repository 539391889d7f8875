"""The Q2 scorer: exact wall-set match per scene (rules in :mod:`bpb_tasks.questions.labels`)."""

from __future__ import annotations

from typing import Literal

from bpb_tasks.billiards.truth import FinalState
from bpb_tasks.questions.ids import wall_name
from bpb_tasks.questions.labels import LabelScorer


class Q2Scorer(LabelScorer):
    """One unit per wall (for the per-wall confusion); a scene scores 1 only when all four are
    right."""

    name = "q2"
    task = "q2"
    scene_rule: Literal["mean", "all"] = "all"
    key = "wall"
    parse_key = staticmethod(wall_name)

    def labels(self, truth: FinalState) -> dict[str, str]:
        return {t.wall: t.answer for t in truth.q2}
