"""The diagnostic: is a model right because nothing happens, or because it sees the hit?

Per run: accuracy on scenes where the cue ball hits a ball, on scenes where it hits none, and
the share of true hits answered "none" (the task's stasis rate). Answered scenes only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pandas as pd

from bpb_core.results.tables import RUN_COLUMNS
from bpb_firsthit.scorer import NONE

if TYPE_CHECKING:
    from bpb_core.interfaces import ScoredResults

RATES = ("hit_accuracy", "none_accuracy", "hit_said_none")


def outcomes(units: pd.DataFrame) -> pd.DataFrame:
    """The table (see the module docstring), one row per run that answered firsthit."""
    frame = units[(units["task"] == "firsthit") & (units["status"] == "ok")]
    frame = frame.assign(hit=frame["truth"] != NONE, said_none=frame["pred"] == NONE)
    groups = frame.groupby([*RUN_COLUMNS, "hit"], observed=True)
    acc = groups["correct"].mean().unstack("hit")
    said_none = frame[frame["hit"]].groupby(RUN_COLUMNS, observed=True)["said_none"].mean()
    counts = groups.size().unstack("hit").fillna(0).astype("int64")
    out = pd.DataFrame(
        {
            "hit_accuracy": acc.get(True),
            "none_accuracy": acc.get(False),
            "hit_said_none": said_none,
            "hits": counts.get(True, 0),
            "no_hits": counts.get(False, 0),
        },
        index=acc.index,
    )
    out[["hits", "no_hits"]] = out[["hits", "no_hits"]].fillna(0).astype("int64")
    return out.reset_index()


class FirstHitOutcomes:
    """Diagnostic plugin ``firsthit_outcomes``."""

    name = "firsthit_outcomes"
    title = "First hit outcomes"
    percent: tuple[str, ...] = RATES
    terminal: tuple[str, ...] = (*RATES, "hits", "no_hits")

    def table(self, results: ScoredResults) -> pd.DataFrame:
        return outcomes(results.units)

    def chart(self, table: pd.DataFrame) -> bytes | None:
        """Grouped bars per run: accuracy with a hit, without one, and hits said 'none'."""
        from bpb_core.report.charts import figure, names_of, png

        fig, axes = figure(1, 1, (9.0, 1.8 + 0.6 * len(table)))
        ax = axes[0, 0]
        ys = list(range(len(table)))
        colours = ("#1f77b4", "#7f7f7f", "#d62728")
        for k, (column, colour) in enumerate(zip(RATES, colours, strict=True)):
            values = 100 * table[column].fillna(0).to_numpy(dtype=float)
            ax.barh([y + (k - 1) * 0.27 for y in ys], values, 0.26, color=colour, label=column)
        ax.set_yticks(ys, names_of(table), fontsize=8)
        ax.set_xlim(0, 100)
        ax.set_xlabel("share of answered scenes (%)")
        ax.set_title("First hit: accuracy with and without a hit")
        ax.legend(loc="lower right", fontsize=8)
        return png(fig)
