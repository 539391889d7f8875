"""The Q2 scorer: exact wall-set match per scene (rules in :mod:`bpb_tasks.questions.labels`),
and the confusion diagnostic, pooled and per wall."""

from __future__ import annotations

from typing import Literal

from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.questions.answers import wall_name
from bpb_tasks.questions.labels import ConfusionDiagnostic, LabelScorer


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


class Q2Confusion(ConfusionDiagnostic):
    """Q2 confusion pooled over the walls (``all``) and per wall, per run."""

    name = "q2_confusion"
    title = "Q2 confusion (all walls and per wall; answered units)"
    task = "q2"
    per_unit = True
