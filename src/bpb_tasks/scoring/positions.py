"""Scorer for Q3: every ball's position at the horizon.

A ball is right when the predicted centre lies within one ball radius of the true centre
(Euclidean distance <= R), or when both the prediction and the truth are ``null`` (pocketed). A
position where the truth is ``null``, or ``null`` where the truth is a position, is wrong. A
position must be a list of two finite numbers; anything else is an invalid prediction (wrong).
Missing balls and balls listed twice are wrong; unknown ids and extra keys are ignored; only
answers with status ``ok`` can be right. A scene's score is the share of its balls that are right.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Literal

import numpy as np
import pandas as pd

from bpb_core.scene import FinalState, Scene
from bpb_core.units import INVALID, NAN, UnitRow, entries
from bpb_tasks.scoring.labels import ball_id, collect

XY = tuple[float, float]


def position(value: object) -> tuple[str, XY]:
    """(``pos``/``null``/``?``, (x, y)) for a predicted ``pos`` value."""
    if value is None:
        return "null", (NAN, NAN)
    if isinstance(value, (list, tuple)) and len(value) == 2:
        x, y = value
        numbers = all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in (x, y))
        if numbers and math.isfinite(x) and math.isfinite(y):
            return "pos", (float(x), float(y))
    return INVALID, (NAN, NAN)


class Q3Scorer:
    """Q3: per-ball position within the ball radius (see the module docstring)."""

    name = "q3"
    task = "q3"
    scene_rule: Literal["mean", "all"] = "mean"

    def units(
        self, answer: Mapping[str, Any] | None, final: FinalState, scene: Scene
    ) -> list[UnitRow]:
        radius = scene.physics.ball_radius
        starts = {str(b.id): b.pos for b in scene.balls}
        truth = {str(p.id): p.pos for p in final.predictions}
        found, dups = collect(entries(answer, "predictions"), "id", set(truth), ball_id)
        rows = []
        for name, true_pos in truth.items():
            pred, (px, py) = (
                position(found[name].get("pos")) if name in found else (None, (NAN, NAN))
            )
            tx, ty = true_pos if true_pos is not None else (NAN, NAN)
            sx, sy = starts.get(name, (NAN, NAN))
            rows.append(
                UnitRow(
                    unit=name,
                    truth="null" if true_pos is None else "pos",
                    pred=pred,
                    duplicate=name in dups,
                    truth_x=tx,
                    truth_y=ty,
                    pred_x=px,
                    pred_y=py,
                    start_x=sx,
                    start_y=sy,
                    radius=radius,
                )
            )
        return rows

    def score(self, units: pd.DataFrame) -> pd.DataFrame:
        """``distance`` between predicted and true centres; ``correct`` by the radius rule."""
        ok = (units["status"] == "ok").to_numpy(dtype=bool)
        ok = ok & ~units["duplicate"].to_numpy(dtype=bool)
        dx = units["pred_x"].to_numpy(dtype=float) - units["truth_x"].to_numpy(dtype=float)
        dy = units["pred_y"].to_numpy(dtype=float) - units["truth_y"].to_numpy(dtype=float)
        distance = np.hypot(dx, dy)
        near = distance <= units["radius"].to_numpy(dtype=float)  # NaN compares False
        both_null = ((units["truth"] == "null") & (units["pred"] == "null")).to_numpy(dtype=bool)
        correct = ok & (near | both_null)
        return pd.DataFrame({"correct": correct, "distance": distance}, index=units.index)
