"""PNG charts of a report, drawn with matplotlib (imported lazily, Agg backend).

Each function takes a derived frame and returns PNG bytes. Baseline runs are drawn in grey with
hatching (bars) or dashed lines and their names carry a ``[baseline]`` mark, so models are read
against the floors and the ceiling.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from bpb_core.registration import SuiteInfo

_MODEL_COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b"]
_BASELINE_GREYS = ["#444444", "#9a9a9a", "#6e6e6e", "#bdbdbd"]
_BASELINE_LINES = ["--", ":", "-.", (0, (6, 2, 1, 2))]
_BASELINE_HATCHES = ["//", "..", "xx", "\\\\"]
_BASELINE_MARKERS = ["s", "^", "D", "v"]


def label(run: str, baseline: bool) -> str:
    """Display name of a run; baselines are marked."""
    return f"{run} [baseline]" if baseline else run


def names_of(frame: pd.DataFrame) -> list[str]:
    """Display names of the rows of a frame with columns run, baseline."""
    pairs = zip(frame["run"], frame["baseline"], strict=True)
    return [label(str(run), bool(baseline)) for run, baseline in pairs]


def figure(nrows: int, ncols: int, size: tuple[float, float]) -> tuple[Figure, Any]:
    """A constrained-layout figure with a grid of axes (Agg backend, nothing global)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=110, layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    return fig, axes


def png(fig: Figure) -> bytes:
    """The figure as PNG bytes."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()


def run_styles(runs: pd.DataFrame) -> dict[str, dict[str, Any]]:
    """Colour, line style and hatch per run (``runs`` has columns run, baseline)."""
    styles: dict[str, dict[str, Any]] = {}
    models = baselines = 0
    for row in runs.drop_duplicates("run").itertuples():
        if row.baseline:
            k = baselines % len(_BASELINE_GREYS)
            styles[str(row.run)] = {
                "color": _BASELINE_GREYS[k],
                "ls": _BASELINE_LINES[k],
                "hatch": _BASELINE_HATCHES[k],
                "marker": _BASELINE_MARKERS[k],
            }
            baselines += 1
        else:
            colour = _MODEL_COLOURS[models % len(_MODEL_COLOURS)]
            styles[str(row.run)] = {"color": colour, "ls": "-", "hatch": "", "marker": "o"}
            models += 1
    return styles


def accuracy_vs_horizon(
    accuracy: pd.DataFrame,
    leaderboard_order: list[str],
    suites: Sequence[SuiteInfo] = (),
    titles: Mapping[str, str] | None = None,
) -> bytes:
    """One panel per task (and per suite): accuracy against horizon, one line per run."""
    titles = titles or {}
    frame = accuracy.copy()
    panels: dict[str, pd.DataFrame] = {
        str(task): frame[frame["task"] == task] for task in sorted(frame["task"].unique())
    }
    for suite in suites:
        panels[suite.name] = _suite_by_horizon(frame, suite)
    ncols = min(len(panels), 2)
    nrows = (len(panels) + ncols - 1) // ncols
    fig, axes = figure(nrows, ncols, (6.2 * ncols, 3.6 * nrows))
    styles = run_styles(frame[["run", "baseline"]])
    for ax, (name, data) in zip(axes.flat, panels.items(), strict=False):
        for run in leaderboard_order:
            rows = data[data["run"] == run].sort_values("horizon")
            if rows.empty:
                continue
            style = styles[run]
            ax.plot(
                rows["horizon"], 100 * rows["accuracy"], color=style["color"], ls=style["ls"],
                marker=style["marker"], label=label(run, bool(rows["baseline"].iloc[0])),
            )  # fmt: skip
        ax.set_title(titles.get(name, name))
        ax.set_xlabel("horizon (s)")
        ax.set_ylabel("accuracy (%)")
        ax.set_ylim(-3, 103)
        ax.set_xticks(sorted(frame["horizon"].unique()))
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(panels) :]:
        ax.set_visible(False)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 4), fontsize=8)
    return png(fig)


def _suite_by_horizon(accuracy: pd.DataFrame, suite: SuiteInfo) -> pd.DataFrame:
    wide = accuracy.pivot_table(
        index=["run", "baseline", "horizon"], columns="task", values="accuracy", observed=True
    )
    if not set(suite.weights) <= set(wide.columns):
        return pd.DataFrame(columns=["run", "baseline", "horizon", "accuracy"])
    wide["accuracy"] = sum(w * wide[t] for t, w in suite.weights.items())
    return wide[["accuracy"]].reset_index()


def leaderboards(
    board: pd.DataFrame,
    metrics: Sequence[str],
    ci: pd.DataFrame | None = None,
    titles: Mapping[str, str] | None = None,
) -> bytes:
    """One leaderboard per metric (each task, then each suite): horizontal bars, best on
    top."""
    titles = titles or {}
    ncols = min(len(metrics), 2)
    nrows = (len(metrics) + ncols - 1) // ncols
    fig, axes = figure(nrows, ncols, (6.2 * ncols, (0.8 + 0.42 * len(board)) * nrows))
    styles = run_styles(board[["run", "baseline"]])
    for ax in list(axes.flat)[len(metrics) :]:
        ax.set_visible(False)
    for ax, metric in zip(axes.flat, metrics, strict=False):
        ranked = board.dropna(subset=[metric]).sort_values(metric)
        values = 100 * ranked[metric].to_numpy(dtype=float)
        ys = range(len(ranked))
        colours = [styles[str(r)]["color"] for r in ranked["run"]]
        hatches = [styles[str(r)]["hatch"] for r in ranked["run"]]
        bars = ax.barh(list(ys), values, color=colours, edgecolor="white")
        for bar, hatch in zip(bars, hatches, strict=True):
            bar.set_hatch(hatch)
        ends = values.copy()
        if ci is not None:
            ends = np.fmax(ends, _error_bars(ax, ranked, ci, metric))
        for y, value, end in zip(ys, values, ends, strict=True):
            ax.text(end + 1.5, y, f"{value:.1f}%", va="center", fontsize=8)
        ax.set_yticks(list(ys), names_of(ranked), fontsize=8)
        ax.set_xlim(0, 114)
        ax.set_xticks([0, 20, 40, 60, 80, 100])
        ax.set_xlabel("mean accuracy over horizons (%)")
        ax.set_title(titles.get(metric, metric) + " leaderboard", fontsize=10)
        ax.grid(axis="x", alpha=0.3)
    return png(fig)


def _error_bars(ax: Any, ranked: pd.DataFrame, ci: pd.DataFrame, metric: str) -> Any:
    rows = ci[ci["metric"] == metric].set_index("run")
    lo = 100 * rows["lo"].reindex(ranked["run"]).to_numpy(dtype=float)
    hi = 100 * rows["hi"].reindex(ranked["run"]).to_numpy(dtype=float)
    mid = 100 * ranked[metric].to_numpy(dtype=float)
    err = [mid - lo, hi - mid]
    ax.errorbar(mid, range(len(ranked)), xerr=err, fmt="none", ecolor="black", capsize=3, lw=1)
    return np.nan_to_num(hi, nan=0.0)
