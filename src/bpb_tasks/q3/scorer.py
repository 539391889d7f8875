"""The Q3 scorer: every ball's position at the horizon.

A ball is right when the predicted centre lies within one ball radius of the true centre
(Euclidean distance <= R), or when both the prediction and the truth are ``null`` (pocketed). A
position where the truth is ``null``, or ``null`` where the truth is a position, is wrong. A
position must be a list of two finite numbers; anything else is an invalid prediction (wrong).
Missing balls and balls listed twice are wrong; unknown ids and extra keys are ignored; only
answers with status ``ok`` can be right. A scene's score is the share of its balls that are right.

Diagnostics of how far predicted final positions are from the truth: ``q3_distance`` (and
``q3_distance_by_horizon``): the error in metres where both prediction and truth are positions,
with the count of balls where exactly one side is ``null``. ``q3_tolerance``: Q3 accuracy if a
ball counted as right within k radii instead of one, over the answered scenes (like the
leaderboards' lead view: a call that never returned an answer is left out, not counted wrong, so
missing answers cannot lower or rank a curve).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pandas as pd
from PIL import ImageDraw

from bpb_core.picture import ScenePicture, font, shape
from bpb_core.results.tables import RUN_COLUMNS, UNANSWERED
from bpb_core.scored_units import INVALID, NAN, UnitRow, entries
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.questions.answers import ball_id
from bpb_tasks.questions.labels import collect

if TYPE_CHECKING:
    from bpb_core.interfaces import ScoredResults

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


COLUMNS: dict[str, str] = {
    "truth_x": "float64",
    "truth_y": "float64",
    "pred_x": "float64",
    "pred_y": "float64",
    "start_x": "float64",
    "start_y": "float64",
    "radius": "float64",
}
"""Q3's own unit columns: true, predicted and starting centre (NaN when absent), ball radius."""

TRUTH_COLOUR = (255, 212, 0)
PRED_COLOUR = (255, 80, 255)  # magenta: no ball, path or trajectory mark uses it
LINK_COLOUR = (255, 255, 255)


class Q3Scorer:
    """Q3: per-ball position within the ball radius (see the module docstring)."""

    name = "q3"
    task = "q3"
    scene_rule: Literal["mean", "all"] = "mean"
    columns: Mapping[str, str] = COLUMNS

    def units(
        self, answer: Mapping[str, Any] | None, truth: FinalState, scene: Scene
    ) -> list[UnitRow]:
        radius = scene.physics.ball_radius
        starts = {str(b.id): b.pos for b in scene.balls}
        true_pos = {str(p.id): p.pos for p in truth.predictions}
        found, dups = collect(entries(answer, "predictions"), "id", set(true_pos), ball_id)
        rows = []
        for name, where in true_pos.items():
            pred, (px, py) = (
                position(found[name].get("pos")) if name in found else (None, (NAN, NAN))
            )
            tx, ty = where if where is not None else (NAN, NAN)
            sx, sy = starts.get(name, (NAN, NAN))
            rows.append(
                UnitRow(
                    unit=name,
                    truth="null" if where is None else "pos",
                    pred=pred,
                    duplicate=name in dups,
                    values=(tx, ty, px, py, sx, sy, radius),
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

    def explain(self, rows: pd.DataFrame) -> list[str]:
        """``ball 3: off by 0.120 m (4.2 R)`` (or what was said instead) per wrong ball."""
        lines = []
        r: Any
        for r in rows[~rows["correct"].astype(bool)].itertuples():
            if r.truth == "null" or r.pred != "pos":
                truth = "pocketed" if r.truth == "null" else f"({r.truth_x:.3f}, {r.truth_y:.3f})"
                pred = {"null": "pocketed", "?": "invalid"}.get(str(r.pred), "no answer")
                pred = f"({r.pred_x:.3f}, {r.pred_y:.3f})" if r.pred == "pos" else pred
                lines.append(f"ball {r.unit}: predicted {pred}, truth {truth}")
            else:
                off = f"{r.distance:.3f} m ({r.distance / r.radius:.1f} R)"
                lines.append(f"ball {r.unit}: off by {off}")
        return lines

    def overlay(self, picture: ScenePicture, rows: pd.DataFrame) -> None:
        """True (yellow square) and predicted (magenta triangle) centres joined by a line:
        shapes the trajectory image does not use (its rings, diamonds and crosses mark
        contacts and pocketings)."""
        r = (float(rows["radius"].iloc[0]) if len(rows) else 0.028575) * picture.scale
        width = max(2, round(r / 6))
        face = font(max(12, round(r * 0.9)))
        draw = ImageDraw.Draw(picture.image)

        def point(x: float, y: float) -> tuple[float, float] | None:
            return None if math.isnan(x) or math.isnan(y) else picture.to_px(x, y)

        row: Any
        for row in rows.itertuples():
            truth = point(float(row.truth_x), float(row.truth_y))
            pred = point(float(row.pred_x), float(row.pred_y))
            unit = str(row.unit)
            if truth and pred:
                draw.line((*truth, *pred), fill=LINK_COLOUR, width=max(1, width // 2))
            if truth:
                tx, ty = truth
                draw.polygon(shape("square", tx, ty, r * 1.1), outline=TRUTH_COLOUR, width=width)
                draw.text((tx + r * 1.2, ty - r * 1.2), unit, fill=TRUTH_COLOUR, font=face)
            if pred:
                x, y = pred
                draw.polygon(shape("triangle", x, y, r * 1.1), outline=PRED_COLOUR, width=width)
                draw.text((x + r * 1.2, y + r * 0.2), unit, fill=PRED_COLOUR, font=face)
        picture.explain("true final position", TRUTH_COLOUR, "square")
        picture.explain("predicted position", PRED_COLOUR, "triangle")
        picture.explain("error", LINK_COLOUR, "line")


DEFAULT_TOLERANCES = (0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0)
"""Tolerances of :func:`tolerance_curve`, in ball radii (1.0 is the Q3 rule)."""


def distance_errors(units: pd.DataFrame, *, by_horizon: bool = False) -> pd.DataFrame:
    """Q3 position error (m) where both prediction and truth are positions.

    Returns:
        Columns ``run, adapter, model, baseline[, horizon], mean, median, p90, max, n,
        null_mismatch`` (``null_mismatch``: answered balls where exactly one side is null).
    """
    keys = [*RUN_COLUMNS, "horizon"] if by_horizon else list(RUN_COLUMNS)
    frame = units[(units["task"] == "q3") & (units["status"] == "ok")]
    both = frame[frame["distance"].notna()]
    stats = both.groupby(keys, observed=True)["distance"].agg(
        mean="mean", median="median", p90=lambda d: d.quantile(0.9), max="max", n="size"
    )
    mismatch = (frame["truth"] == "null") != (frame["pred"] == "null")
    mismatch &= frame["pred"].isin(["pos", "null"])
    counts = mismatch.groupby([frame[k] for k in keys], observed=True).sum()
    stats["null_mismatch"] = counts.reindex(stats.index).fillna(0).astype("int64")
    return stats.reset_index()


def tolerance_curve(
    units: pd.DataFrame, tolerances: tuple[float, ...] = DEFAULT_TOLERANCES
) -> pd.DataFrame:
    """Q3 accuracy (pooled over balls) if a ball counted as right within k radii, over the
    answered units: a unit whose call never returned an answer (``api_error``, or never sent)
    is left out; a parse error stays wrong.

    Returns:
        Columns ``run, adapter, model, baseline, tolerance`` (in radii), ``tolerance_m``
        (metres, for the first row's radius), ``accuracy`` (NaN for a run with no answered Q3
        unit) and ``balls`` (the answered units it is over). At ``tolerance == 1`` this is the
        Q3 per-ball accuracy pooled over the answered scenes.
    """
    frame = units[units["task"] == "q3"]
    frame = frame[~frame["status"].isin(UNANSWERED) & ~frame["duplicate"].astype(bool)]
    ok = (frame["status"] == "ok").to_numpy(dtype=bool)
    both_null = ((frame["truth"] == "null") & (frame["pred"] == "null")).to_numpy(dtype=bool)
    ratio = (frame["distance"] / frame["radius"]).to_numpy(dtype=float)
    ks = np.asarray(tolerances, dtype=float)
    hits = ok[:, None] & (both_null[:, None] | (ratio[:, None] <= ks[None, :]))
    wide = pd.DataFrame(hits, columns=ks, index=frame.index)
    wide[RUN_COLUMNS] = frame[RUN_COLUMNS]
    runs = units.loc[units["task"] == "q3", RUN_COLUMNS].drop_duplicates()
    grouped = wide.groupby(RUN_COLUMNS, observed=True)
    means = grouped[list(ks)].mean()
    counts = grouped.size().rename("balls")
    index = pd.MultiIndex.from_frame(runs)  # every run with Q3 units, answered or not
    means = means.reindex(index)
    long = means.melt(ignore_index=False, var_name="tolerance", value_name="accuracy")
    long = long.join(counts.reindex(index).fillna(0).astype("int64"))
    long = long.reset_index().sort_values(["run", "tolerance"], kind="stable")
    radius = float(units.loc[units["task"] == "q3", "radius"].iloc[0]) if len(runs) else math.nan
    long["tolerance"] = long["tolerance"].astype("float64")
    long.insert(len(RUN_COLUMNS) + 1, "tolerance_m", long["tolerance"] * radius)
    return long.reset_index(drop=True)


class Q3Distance:
    """Q3 distance error per run (m)."""

    name = "q3_distance"
    title = "Q3 distance error (m)"
    percent: tuple[str, ...] = ()
    terminal: tuple[str, ...] = ()

    def table(self, results: ScoredResults) -> pd.DataFrame:
        return distance_errors(results.units)

    def chart(self, table: pd.DataFrame) -> bytes | None:
        return None


class Q3DistanceByHorizon(Q3Distance):
    """Q3 distance error per run and horizon (m)."""

    name = "q3_distance_by_horizon"
    title = "Q3 distance error by horizon (m)"

    def table(self, results: ScoredResults) -> pd.DataFrame:
        return distance_errors(results.units, by_horizon=True)


class Q3Tolerance:
    """Q3 accuracy against the tolerance, with its chart."""

    name = "q3_tolerance"
    title = "Q3 tolerance curve"
    percent: tuple[str, ...] = ("accuracy",)
    terminal: tuple[str, ...] = ()

    def table(self, results: ScoredResults) -> pd.DataFrame:
        return tolerance_curve(results.units)

    def chart(self, table: pd.DataFrame) -> bytes | None:
        """Q3 accuracy against the tolerance (in ball radii), one line per run."""
        from bpb_core.report.charts import figure, label, png, run_styles

        runs = table["run"].nunique()
        fig, axes = figure(1, 1, (7.0, 3.6 + 0.2 * ((runs + 2) // 3)))
        ax = axes[0, 0]
        styles = run_styles(table[["run", "baseline"]])
        for run, rows in table.groupby("run", observed=True, sort=False):
            style = styles[str(run)]
            ax.plot(
                rows["tolerance"], 100 * rows["accuracy"], color=style["color"],
                ls=style["ls"], marker=style["marker"], ms=3,
                label=label(str(run), bool(rows["baseline"].iloc[0])),
            )  # fmt: skip
        ax.axvline(1.0, color="black", lw=0.8, ls=":")
        ax.text(1.05, 2, "Q3 rule (1 R)", fontsize=8)
        ax.set_xlabel("tolerance (ball radii)")
        ax.set_ylabel("Q3 accuracy, answered balls (%)")
        ax.set_ylim(-3, 103)
        ax.set_title("Q3 tolerance curve")
        ax.grid(alpha=0.3)
        fig.legend(loc="outside lower center", ncols=min(runs, 3), fontsize=8, frameon=False)
        return png(fig)
