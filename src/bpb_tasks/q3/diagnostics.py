"""Diagnostics of Q3: how far predicted final positions are from the truth.

``q3_distance`` (and ``q3_distance_by_horizon``): the error in metres where both prediction and
truth are positions, with the count of balls where exactly one side is ``null``.
``q3_tolerance``: Q3 accuracy if a ball counted as right within k radii instead of one, over the
answered scenes (like the leaderboards' lead view: a call that never returned an answer is left
out, not counted wrong, so missing answers cannot lower or rank a curve).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from bpb_core.results.tables import RUN_COLUMNS, UNANSWERED

if TYPE_CHECKING:
    from bpb_core.interfaces import ScoredResults

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
