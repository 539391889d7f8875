"""PNG charts of a report, drawn with matplotlib (imported lazily, Agg backend).

Each function takes a derived frame and returns PNG bytes. Models get one colour-blind-safe
colour each (Okabe-Ito); baseline runs are drawn in grey with hatching (bars) or dashed lines
and their names carry a ``[baseline]`` mark, so models are read against the floors and the
ceiling.

Accuracy by horizon (:func:`by_horizon_figure`) is in the paper's form: grouped bars per task,
one group per horizon, one bar per run, every bar labelled with its value. Completeness is drawn,
not hidden: a cell under 100% answered carries a ``*`` after its value; a cell under the
threshold is drawn as a pale outline labelled "left out" with its answered share, so a stopped
run never reads as "accuracy falls with horizon".
"""

from __future__ import annotations

import io
import textwrap
from collections.abc import Collection, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from bpb_core.results.tables import level

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from bpb_core.registry import SuiteInfo


# Okabe-Ito: distinguishable with every common colour-vision deficiency and in greyscale order.
_MODEL_COLOURS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"]
# After each round of the colours the next variant: (hatch, line style, marker). 7 colours x 4
# variants keep 28 models apart in bars and in lines, more than the paper's 17.
_VARIANTS: list[tuple[str, Any, str]] = [
    ("", "-", "o"),
    ("//", "--", "s"),
    ("..", ":", "^"),
    ("xx", "-.", "D"),
]
_BASELINE_COLOURS = ["#4d4d4d", "#969696", "#737373", "#bdbdbd"]
_BASELINE_VARIANTS: list[tuple[str, Any, str]] = [
    ("//", "--", "s"),
    ("..", ":", "^"),
    ("xx", "-.", "D"),
    ("\\\\", (0, (6, 2, 1, 2)), "v"),
]
SHORT_FACE = "#f0f0f0"
# the width of one bar of the by-horizon chart: its value label, rotated, at 5.5 pt plus a gap
_BAR_INCHES = 0.115


def label(run: str, baseline: bool) -> str:
    """Display name of a run in a chart; baselines are marked."""
    return f"{run} [baseline]" if baseline else run


def names_of(frame: pd.DataFrame) -> list[str]:
    """Display names of the rows of a frame with columns run, baseline."""
    pairs = zip(frame["run"], frame["baseline"], strict=True)
    return [label(str(run), bool(baseline)) for run, baseline in pairs]


def figure(nrows: int, ncols: int, size: tuple[float, float], dpi: int = 110) -> tuple[Figure, Any]:
    """A constrained-layout figure with a grid of axes. Nothing global: no pyplot, and the
    process's backend is left alone (``savefig`` draws PNG with Agg whatever it is)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=dpi, layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    return fig, axes


def png(fig: Figure) -> bytes:
    """The figure as PNG bytes, its texts drawn as written (:func:`_as_written`)."""
    _as_written(fig)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()


def _as_written(fig: Figure) -> None:
    """Draw every text of ``fig`` as written. matplotlib reads text between two ``$`` as TeX
    math, so a run or title such as ``a$\\frac{$`` stopped the report and ``$x$`` came out in
    italics; names, titles and plugins' own texts are shown as they are. Math stays on for the
    numbers tick formatters write (a log axis's ``$\\mathdefault{10^{-3}}$``), and it is set on
    each text, not in ``rcParams``, which belong to the calling program."""
    from matplotlib.text import Text

    numbers = _formatted(fig)
    for text in fig.findobj(Text):
        if text not in numbers:
            text.set_parse_math(False)


def _formatted(fig: Figure) -> set[Any]:
    """The texts of ``fig`` that matplotlib's number formatters write: offsets and tick labels,
    except labels given as strings (``set_yticks(ys, names)`` makes a ``FuncFormatter``
    returning them, ``set_ticklabels`` alone a ``FixedFormatter``)."""
    from matplotlib.ticker import FixedFormatter, FuncFormatter

    found: set[Any] = set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            found.add(axis.offsetText)
            for ticks, formatter in (
                (axis.get_major_ticks(), axis.get_major_formatter()),
                (axis.get_minor_ticks(), axis.get_minor_formatter()),
            ):
                if not isinstance(formatter, (FixedFormatter, FuncFormatter)):
                    found.update(t for tick in ticks for t in (tick.label1, tick.label2))
    return found


def run_styles(runs: pd.DataFrame) -> dict[str, dict[str, Any]]:
    """Colour, line style and hatch per run (``runs`` has columns run, baseline), assigned in
    the order of the run names so that every chart of a report agrees."""
    styles: dict[str, dict[str, Any]] = {}
    models = baselines = 0
    # by name, not by the frame's order, so a run has the same style in every chart
    ordered = runs.assign(run=runs["run"].astype(str)).drop_duplicates("run").sort_values("run")
    for row in ordered.itertuples():
        if row.baseline:
            # a shifted variant per round of greys: 16 baselines keep apart
            k, greys = baselines, len(_BASELINE_COLOURS)
            colour = _BASELINE_COLOURS[k % greys]
            hatch, ls, marker = _BASELINE_VARIANTS[(k + k // greys) % len(_BASELINE_VARIANTS)]
            baselines += 1
        else:
            colour = _MODEL_COLOURS[models % len(_MODEL_COLOURS)]
            variant = (models // len(_MODEL_COLOURS)) % len(_VARIANTS)
            hatch, ls, marker = _VARIANTS[variant]
            models += 1
        styles[str(row.run)] = {"color": colour, "ls": ls, "hatch": hatch, "marker": marker}
    return styles


def leaderboard_figure(
    board: pd.DataFrame,
    metrics: Sequence[str],
    ci: pd.DataFrame | None = None,
    titles: Mapping[str, str] | None = None,
    *,
    xlabel: str = "mean accuracy over horizons (%)",
    no_value: str = "left out (too incomplete)",
    unasked: Mapping[str, Collection[str]] | None = None,
) -> Figure:
    """One leaderboard per metric (each task, then each suite): horizontal bars, best on
    top, every baseline also drawn as a dashed line across the panel (the floors and the
    ceiling on the same axis); a zero is drawn as a tick on the axis so it reads as a value;
    runs with no value are named under the axis after ``no_value``, except those ``unasked``
    lists for the metric (runs not asked it), which are named after "not asked"."""
    unasked = unasked or {}
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
        for y, value, colour in zip(ys, values, colours, strict=True):
            if value == 0:
                ax.plot([0.6, 0.6], [y - 0.4, y + 0.4], color=colour, lw=3, solid_capstyle="butt")
        ends = values.copy()
        if ci is not None:
            ends = np.fmax(ends, _error_bars(ax, ranked, ci, metric))
        for y, value, end in zip(ys, values, ends, strict=True):
            ax.text(end + 1.5, y, f"{value:.1f}%", va="center", fontsize=8)
        ax.set_yticks(list(ys), names_of(ranked), fontsize=8)
        ax.set_xlim(0, 114)
        ax.set_xticks([0, 20, 40, 60, 80, 100])
        for row in ranked[ranked["baseline"].astype(bool)].to_dict(orient="records"):
            style = styles[str(row["run"])]  # the floors and the ceiling across the panel
            ax.axvline(100 * float(row[metric]), color=style["color"], ls="--", lw=0.8, zorder=0)
        missing = board.loc[board[metric].isna(), "run"].astype(str).tolist()
        others = set(unasked.get(metric, ()))
        left_out = [run for run in missing if run not in others]
        not_asked = [run for run in missing if run in others]
        note = f"\n{_wrapped(f'{no_value}: ' + ', '.join(left_out))}" if left_out else ""
        note += f"\n{_wrapped('not asked: ' + ', '.join(not_asked))}" if not_asked else ""
        ax.set_xlabel(xlabel + note, fontsize=8)
        ax.set_title(titles.get(metric, metric), fontsize=10)
        ax.grid(axis="x", alpha=0.3)
    return fig


def _wrapped(text: str) -> str:
    """A list of run names under a 6.2-inch panel, in lines that fit it at 8 pt."""
    return "\n".join(textwrap.wrap(text, 90, break_on_hyphens=False))


def _error_bars(ax: Any, ranked: pd.DataFrame, ci: pd.DataFrame, metric: str) -> Any:
    rows = ci[ci["metric"] == metric].set_index("run")
    lo = 100 * rows["lo"].reindex(ranked["run"]).to_numpy(dtype=float)
    hi = 100 * rows["hi"].reindex(ranked["run"]).to_numpy(dtype=float)
    mid = 100 * ranked[metric].to_numpy(dtype=float)
    err = [mid - lo, hi - mid]
    ax.errorbar(mid, range(len(ranked)), xerr=err, fmt="none", ecolor="black", capsize=3, lw=1)
    return np.nan_to_num(hi, nan=0.0)


def suite_by_horizon(accuracy: pd.DataFrame, suite: SuiteInfo) -> pd.DataFrame:
    """A suite's weighted accuracy per (run, horizon), with the least complete task's
    completeness (empty when a task of it is absent)."""
    keys = ["run", "baseline", "horizon"]
    cells = accuracy.assign(run=accuracy["run"].astype(str)).set_index([*keys, "task"])
    wide = cells["accuracy"].unstack("task")  # keeps cells with no answer (NaN): drawn left out
    done = cells["completeness"].unstack("task")
    if not set(suite.weights) <= set(wide.columns):
        return pd.DataFrame(columns=[*keys, "accuracy", "completeness"])
    out = pd.DataFrame({"accuracy": sum(w * wide[t] for t, w in suite.weights.items())})
    out["completeness"] = done[list(suite.weights)].min(axis=1)
    return out.reset_index()


def by_horizon_figure(
    accuracy: pd.DataFrame,
    order: Sequence[str],
    suites: Sequence[SuiteInfo] = (),
    titles: Mapping[str, str] | None = None,
    *,
    min_complete: float = 0.9,
    view: str = "answered only",
) -> Figure:
    """One panel per task (and per suite): grouped bars by horizon, one bar per run in
    ``order``. The figure widens with the bars (runs x horizons) so that no two value labels
    overlap, and the legend takes as many columns as the width holds."""
    titles = titles or {}
    panels = {str(t): accuracy[accuracy["task"] == t] for t in sorted(accuracy["task"].unique())}
    for suite in suites:
        panels[suite.name] = suite_by_horizon(accuracy, suite)
    horizons = sorted(float(h) for h in accuracy["horizon"].unique())
    runs = [r for r in order if r in set(accuracy["run"].astype(str))]
    bars = len(runs) * len(horizons)
    ncols = 1 if bars > 14 or len(panels) == 1 else 2
    nrows = (len(panels) + ncols - 1) // ncols
    # a bar at least as wide as its rotated value label (_BAR_INCHES), plus the axis's margin
    width = max(7.0 if ncols == 1 else 3.5 * ncols, _BAR_INCHES * bars / 0.84 + 1.2)
    legend_cols = max(1, min(len(runs), int(width // 2.4)))
    legend_rows = -(-len(runs) // legend_cols)
    fig, axes = figure(nrows, ncols, (width, 2.6 * nrows + 0.7 + 0.16 * legend_rows))
    styles = run_styles(accuracy[["run", "baseline"]])
    for ax in list(axes.flat)[len(panels) :]:
        ax.set_visible(False)
    for ax, (name, data) in zip(axes.flat, panels.items(), strict=False):
        _panel(ax, data, runs, horizons, styles, min_complete)
        ax.set_title(titles.get(name, name), fontsize=9)
    fig.suptitle(f"Accuracy by horizon ({view})", fontsize=10)
    baseline = accuracy.assign(run=accuracy["run"].astype(str)).groupby("run")["baseline"].first()
    handles = [_handle(styles[r], label(r, bool(baseline[r]))) for r in runs]
    fig.legend(
        handles=handles, loc="outside lower center", ncols=legend_cols, fontsize=7,
        title=f"* under 100% answered; pale = under {100 * min_complete:.0f}%, left out",
        title_fontsize=7, frameon=False,
    )  # fmt: skip
    return fig


def _handle(style: dict[str, Any], text: str) -> Any:
    from matplotlib.patches import Patch

    return Patch(facecolor=style["color"], hatch=style["hatch"], edgecolor="white", label=text)


def _panel(
    ax: Any,
    data: pd.DataFrame,
    runs: Sequence[str],
    horizons: Sequence[float],
    styles: dict[str, dict[str, Any]],
    min_complete: float,
) -> None:
    width = 0.84 / max(len(runs), 1)
    many = len(runs) * len(horizons) > 10
    for k, run in enumerate(runs):
        chosen = data[data["run"] == run].to_dict(orient="records")
        rows = {float(r["horizon"]): dict(r) for r in chosen}
        for j, horizon in enumerate(horizons):
            if horizon in rows:
                x = j - 0.42 + width * (k + 0.5)
                _bar(ax, x, width, rows[horizon], styles[run], min_complete, many)
    ax.set_xticks(range(len(horizons)), [f"{h:g} s" for h in horizons], fontsize=8)
    ax.set_xlim(-0.5, len(horizons) - 0.5)
    ax.set_ylim(0, 118 if many else 112)
    ax.set_yticks([0, 25, 50, 75, 100])
    ax.tick_params(axis="y", labelsize=7)
    ax.set_ylabel("accuracy (%)", fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    ax.set_axisbelow(True)


def _bar(
    ax: Any,
    x: float,
    width: float,
    cell: Mapping[Any, Any],
    style: dict[str, Any],
    min_complete: float,
    many: bool,
) -> None:
    value = 100 * float(cell["accuracy"])
    done = float(cell["completeness"]) if not np.isnan(cell["completeness"]) else 0.0
    grade = level(done, min_complete)
    text_args: dict[str, Any] = {"ha": "center", "va": "bottom", "fontsize": 5.5 if many else 7}
    if many:
        text_args["rotation"] = 90
    if grade == "short" or np.isnan(value):
        ax.bar(x, 100, width, facecolor=SHORT_FACE, edgecolor=style["color"], ls=":", lw=0.6)
        text = f"left out ({100 * done:.0f}% ans.)"
        ax.text(x, 2, text, color="#666666", **{**text_args, "rotation": 90, "fontsize": 5.5})
        return
    bar = ax.bar(x, value, width, color=style["color"], edgecolor="white", lw=0.4)[0]
    bar.set_hatch(style["hatch"])
    if value == 0:  # a zero is a value: a stub on the axis, not an empty slot
        ax.plot([x - width / 2, x + width / 2], [0.6, 0.6], color=style["color"], lw=2.5)
    mark = "*" if grade == "partial" else ""
    ax.text(x, value + 1, f"{value:.0f}{mark}", **text_args)
