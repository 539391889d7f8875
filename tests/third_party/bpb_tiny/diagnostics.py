"""The ``slider_errors`` diagnostic: how far off the positions are and how the counts go wrong."""

from __future__ import annotations

import io
from typing import TYPE_CHECKING

import pandas as pd

from bpb_core.results.tables import RUN_COLUMNS

if TYPE_CHECKING:
    from bpb_core.interfaces import ScoredResults

TASK = "slider_stop"


def error_table(units: pd.DataFrame) -> pd.DataFrame:
    """Per run: ``x_within`` (share of positions within tolerance), ``x_mae`` (mean error, m,
    over usable positions), ``bounce_exact`` (share of exact counts) and ``bounce_bias`` (mean
    predicted minus true count over usable counts). Strict shares: missing or bad answers are
    wrong."""
    frame = units[units["task"] == TASK]
    runs = frame[RUN_COLUMNS].drop_duplicates().set_index("run")
    xs, counts = frame[frame["unit"] == "x"], frame[frame["unit"] == "bounces"]
    usable = counts[counts["status"] == "ok"]
    bias = pd.to_numeric(usable["pred"], errors="coerce") - pd.to_numeric(usable["truth"])
    table = pd.DataFrame(
        {
            "x_within": xs.groupby("run", observed=True)["correct"].mean(),
            "x_mae": xs[xs["status"] == "ok"].groupby("run", observed=True)["distance"].mean(),
            "bounce_exact": counts.groupby("run", observed=True)["correct"].mean(),
            "bounce_bias": bias.groupby(usable["run"], observed=True).mean(),
        }
    )
    out = runs.join(table, how="left").reset_index()
    return out[[*RUN_COLUMNS, "x_within", "x_mae", "bounce_exact", "bounce_bias"]].astype(
        {"x_within": "float64", "x_mae": "float64", "bounce_exact": "float64",
         "bounce_bias": "float64"}
    )  # fmt: skip


class SliderErrors:
    """Position and count errors of ``slider_stop`` per run, with a bar chart."""

    name = "slider_errors"
    title = "Slider: position and wall-hit errors"
    percent: tuple[str, ...] = ("x_within", "bounce_exact")
    terminal: tuple[str, ...] = ("x_within", "bounce_exact", "x_mae")

    def table(self, results: ScoredResults) -> pd.DataFrame:
        """See :func:`error_table`."""
        return error_table(results.units)

    def chart(self, table: pd.DataFrame) -> bytes | None:
        """Two bars per run: share of right positions and of exact counts."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6.0, 0.6 + 0.5 * max(len(table), 1)), dpi=100, layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.subplots()
        ys = range(len(table))
        ax.barh([y - 0.2 for y in ys], 100 * table["x_within"], height=0.4, label="x within")
        ax.barh([y + 0.2 for y in ys], 100 * table["bounce_exact"], height=0.4, label="bounces")
        ax.set_yticks(list(ys), [str(r) for r in table["run"]])
        ax.set_xlim(0, 100)
        ax.set_xlabel("% right")
        ax.legend(loc="lower right")
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", metadata={"Software": None})
        return buffer.getvalue()
