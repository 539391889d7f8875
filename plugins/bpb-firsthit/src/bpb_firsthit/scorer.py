"""The scorer: one unit per scene, right when the named ball (or none) is the first one hit.

Labels are ball ids as text (``"3"``) or ``"none"``; an answer whose ``first`` is neither an id
nor null is an invalid label (wrong). Only answers with status ``ok`` can be right.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Literal

import numpy as np
import pandas as pd

from bpb_core import UnitRow
from bpb_core.scored_units import INVALID
from bpb_firsthit.task import first_hit
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.questions.answers import ball_id

NONE = "none"


def label(answer: Mapping[str, Any] | None) -> str | None:
    """The predicted label of an answer: an id, ``none``, ``?`` (unusable) or ``None``."""
    if not isinstance(answer, Mapping) or "first" not in answer:
        return None
    value = answer["first"]
    if value is None:
        return NONE
    found = ball_id(value)
    return INVALID if found is None else str(found)


class FirstHitScorer:
    """Scorer plugin ``firsthit``."""

    name = "firsthit"
    task = "firsthit"
    scene_rule: Literal["mean", "all"] = "mean"
    columns: Mapping[str, str] = {}

    def units(
        self, answer: Mapping[str, Any] | None, truth: FinalState, scene: Scene
    ) -> list[UnitRow]:
        hit = first_hit(truth)
        return [UnitRow("first", NONE if hit is None else str(hit), label(answer))]

    def score(self, units: pd.DataFrame) -> pd.DataFrame:
        ok = (units["status"] == "ok").to_numpy(dtype=bool)
        same = (units["pred"] == units["truth"]).to_numpy(dtype=bool)
        dup = units["duplicate"].to_numpy(dtype=bool)
        distance = np.full(len(units), np.nan)
        return pd.DataFrame({"correct": ok & same & ~dup, "distance": distance}, index=units.index)

    def explain(self, rows: pd.DataFrame) -> list[str]:
        wrong = rows[~rows["correct"].astype(bool)]
        return [
            f"first hit: {'no answer' if not isinstance(p, str) else f'said {p}'}, truth {t}"
            for p, t in zip(wrong["pred"], wrong["truth"], strict=True)
        ]
