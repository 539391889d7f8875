"""The stasis index: how often a model predicts that nothing happens when something does.

It looks at the three billiards questions together: true contacts (Q1 balls, Q2 walls) labelled
``F``, and balls that truly moved more than one radius (or were pocketed) predicted within one
radius of where they started (Q3). Only answered units count (see
:mod:`bpb_tasks.questions.labels`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from bpb_core.results.tables import RUN_COLUMNS
from bpb_tasks.questions.labels import labelled

if TYPE_CHECKING:
    from bpb_core.interfaces import ScoredResults

SHARES = ("contact_stasis", "q1_stasis", "q2_stasis", "motion_stasis")


def stasis_index(units: pd.DataFrame) -> pd.DataFrame:
    """The stasis index per run.

    Returns:
        One row per run: ``contact_stasis`` (share of true Q1 and Q2 contacts labelled ``F``),
        ``q1_stasis`` and ``q2_stasis`` (the same per task), ``motion_stasis`` (share of balls
        that truly moved more than one radius, or were pocketed, that are predicted within one
        radius of where they started), and the counts ``contacts`` and ``moved`` behind them.
    """
    labels = labelled(units, ("q1", "q2"))
    labels = labels[labels["truth"] == "T"].assign(missed=lambda f: f["pred"] == "F")
    per_task = labels.pivot_table(
        index=RUN_COLUMNS, columns="task", values="missed", aggfunc="mean", observed=True
    ).reindex(columns=["q1", "q2"])
    pooled = labels.groupby(RUN_COLUMNS, observed=True)["missed"].agg(["mean", "size"])
    # answered Q3 units (position or null) of balls that truly moved more than R or were pocketed
    frame = units[(units["task"] == "q3") & (units["status"] == "ok") & ~units["duplicate"]]
    frame = frame[frame["pred"].isin(["pos", "null"])]
    if frame.empty:
        moves = frame.assign(unmoved=pd.Series(dtype=bool))
    else:
        travelled = np.hypot(
            frame["truth_x"] - frame["start_x"], frame["truth_y"] - frame["start_y"]
        )
        frame = frame[(frame["truth"] == "null") | (travelled > frame["radius"])]
        shift = np.hypot(frame["pred_x"] - frame["start_x"], frame["pred_y"] - frame["start_y"])
        moves = frame.assign(unmoved=shift <= frame["radius"])  # a null prediction (NaN) moved
    motion = moves.groupby(RUN_COLUMNS, observed=True)["unmoved"].agg(["mean", "size"])
    out = pd.DataFrame(
        {
            "contact_stasis": pooled["mean"],
            "q1_stasis": per_task["q1"],
            "q2_stasis": per_task["q2"],
            "motion_stasis": motion["mean"],
            "contacts": pooled["size"],
            "moved": motion["size"],
        }
    )
    out[["contacts", "moved"]] = out[["contacts", "moved"]].fillna(0).astype("int64")
    return out.reset_index()


class StasisIndex:
    """Diagnostic ``stasis`` (see the module docstring), with its bar chart."""

    name = "stasis"
    title = "Stasis index"
    percent: tuple[str, ...] = SHARES
    terminal: tuple[str, ...] = ("contact_stasis", "motion_stasis", "contacts", "moved")

    def table(self, results: ScoredResults) -> pd.DataFrame:
        return stasis_index(results.units)

    def chart(self, table: pd.DataFrame) -> bytes | None:
        """Per run: share of true contacts predicted absent and of moved balls predicted
        unmoved (higher = more 'nothing happens' bias), each bar labelled; a zero is drawn as
        a stub, a share with nothing to count ("n/a": not asked, not answered, or no true contact or
        moved ball among the answered units) as no bar."""
        from bpb_core.report.charts import figure, names_of, png

        fig, axes = figure(1, 1, (7.0, 1.3 + 0.5 * len(table)))
        ax = axes[0, 0]
        ranked = table.sort_values("contact_stasis", na_position="first")
        ys = np.arange(len(ranked), dtype=float)
        height = 0.38
        for offset, column, colour, text in (
            (height / 2, "contact_stasis", "#D55E00", "true contacts predicted absent"),
            (-height / 2, "motion_stasis", "#0072B2", "moved balls predicted unmoved"),
        ):
            values = 100 * ranked[column].to_numpy(dtype=float)
            ax.barh(ys + offset, np.nan_to_num(values, nan=0.0), height, color=colour, label=text)
            for y, value in zip(ys + offset, values, strict=True):
                if np.isnan(value):
                    ax.text(
                        1, y, "n/a (no answered unit to count)", va="center", fontsize=7,
                        color="#666666",
                    )  # fmt: skip
                    continue
                if value == 0:
                    ax.plot([0.6, 0.6], [y - height / 2, y + height / 2], color=colour, lw=3)
                ax.text(value + 1, y, f"{value:.1f}%", va="center", fontsize=7)
        ax.set_yticks(ys, names_of(ranked), fontsize=8)
        ax.set_xlim(0, 112)
        ax.set_xticks([0, 20, 40, 60, 80, 100])
        ax.set_xlabel("share (%), answered units only", fontsize=8)
        ax.set_title("Stasis index", fontsize=10)
        ax.grid(axis="x", alpha=0.3)
        ax.set_axisbelow(True)
        fig.legend(loc="outside lower center", ncols=2, fontsize=8, frameon=False)
        return png(fig)
