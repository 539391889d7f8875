"""The ``slider_stop`` scorer: two units per scene, the position and the wall-hit count.

- ``x`` is right when the predicted position is within ``tolerance`` (2% of the track length)
  of the truth; its ``distance`` is the error in metres.
- ``bounces`` is right when the count is exactly the truth; it has no distance.

Only answers with status ``ok`` can be right; a scene scores the share of its two units that are
right. The scorer's own columns carry the numbers the diagnostic and the gallery need.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Literal

import numpy as np
import pandas as pd
from PIL import ImageDraw

from bpb_core.picture import ScenePicture
from bpb_core.scored_units import INVALID, NAN, UnitRow
from bpb_tiny.scene import SliderScene, SliderTruth
from bpb_tiny.task import TOLERANCE_SHARE, read_count, read_position

COLUMNS: dict[str, str] = {"truth_x": "float64", "pred_x": "float64", "tolerance": "float64"}
TRUTH_COLOUR = (20, 160, 60)
PRED_COLOUR = (220, 30, 60)


def _said(answer: Mapping[str, Any] | None, key: str, read: Any) -> str | None:
    """What the answer says under ``key``: ``None`` when silent, INVALID when unusable."""
    if not isinstance(answer, Mapping) or key not in answer:
        return None
    value = read(answer[key])
    return INVALID if value is None else str(value)


class SliderStopScorer:
    """Scores ``slider_stop`` (see the module docstring)."""

    name = "slider_stop"
    task = "slider_stop"
    scene_rule: Literal["mean", "all"] = "mean"
    columns: Mapping[str, str] = COLUMNS

    def units(
        self, answer: Mapping[str, Any] | None, truth: SliderTruth, scene: SliderScene
    ) -> list[UnitRow]:
        """``x`` then ``bounces``."""
        said_x = _said(answer, "x", read_position)
        pred_x = float(said_x) if said_x not in (None, INVALID) else NAN
        tolerance = TOLERANCE_SHARE * scene.length
        x_pred = None if said_x is None else ("x" if said_x != INVALID else INVALID)
        return [
            UnitRow("x", "x", x_pred, values=(truth.x, pred_x, tolerance)),
            UnitRow("bounces", str(truth.bounces), _said(answer, "bounces", read_count),
                    values=(NAN, NAN, NAN)),
        ]  # fmt: skip

    def score(self, units: pd.DataFrame) -> pd.DataFrame:
        """Position within tolerance, count exact; vectorised."""
        ok = (units["status"] == "ok").to_numpy(dtype=bool) & ~units["duplicate"].to_numpy(bool)
        is_x = (units["unit"] == "x").to_numpy(dtype=bool)
        error = np.abs(units["pred_x"].to_numpy(float) - units["truth_x"].to_numpy(float))
        near = error <= units["tolerance"].to_numpy(float)  # NaN compares False
        same = (units["truth"] == units["pred"]).to_numpy(dtype=bool)
        correct = ok & np.where(is_x, near, same)
        distance = np.where(is_x, error, np.nan)
        return pd.DataFrame({"correct": correct, "distance": distance}, index=units.index)

    def explain(self, rows: pd.DataFrame) -> list[str]:
        """One line per wrong unit: what was said and what is true."""
        wrong = rows[~rows["correct"].astype(bool)]
        return [_wrong_text(row) for row in wrong.to_dict(orient="records")]

    def overlay(self, picture: ScenePicture, rows: pd.DataFrame) -> None:
        """The true (ring) and predicted (ring and cross) positions on the track, joined."""
        x_rows = rows[rows["unit"] == "x"]
        if x_rows.empty:
            return
        row = x_rows.iloc[0]
        draw = ImageDraw.Draw(picture.image)
        tx, ty = picture.to_px(float(row["truth_x"]), 0.0)
        if not math.isnan(float(row["pred_x"])):
            px, py = picture.to_px(float(row["pred_x"]), 0.0)
            draw.line((tx, ty - 16, px, py - 16), fill=PRED_COLOUR, width=2)
            _ring(draw, px, py - 16, PRED_COLOUR, cross=True)
            picture.explain("predicted position", PRED_COLOUR, "ring-cross")
        _ring(draw, tx, ty - 16, TRUTH_COLOUR, cross=False)
        picture.explain("true position at the horizon", TRUTH_COLOUR, "ring")


def _wrong_text(row: Mapping[Any, Any]) -> str:
    pred = row["pred"]
    if row["unit"] != "x":
        said = f"said {pred}" if isinstance(pred, str) else "no answer"
        return f"bounces: {said}, truth {row['truth']}"
    said = "invalid" if isinstance(pred, str) else "no answer"
    if not math.isnan(float(row["pred_x"])):
        said = f"said {float(row['pred_x']):.3f} m, off by {float(row['distance']):.3f} m"
    return f"x: {said} (truth {float(row['truth_x']):.3f} m, ±{float(row['tolerance']):g} m)"


def _ring(draw: ImageDraw.ImageDraw, x: float, y: float, colour: Any, *, cross: bool) -> None:
    r = 9
    draw.ellipse((x - r, y - r, x + r, y + r), outline=colour, width=3)
    if cross:
        draw.line((x - r * 0.6, y - r * 0.6, x + r * 0.6, y + r * 0.6), fill=colour, width=3)
