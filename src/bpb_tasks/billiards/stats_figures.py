"""The dataset's ``stats/`` figures: cue-speed histograms and collision counts per horizon.

Drawn with matplotlib's object API on the Agg canvas (no pyplot, no global state), with the PNG
``Software`` metadata removed so the files are byte-identical across runs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Protocol

SPEED_HIST = "stats/cue_speed_hist.png"
COLLISIONS = "stats/collisions.png"
BINS = 20
DPI = 150


class Tally(Protocol):
    """Per-horizon counts (see :class:`bpb_tasks.billiards.family.BilliardsTally`)."""

    scenes: int
    collisions: int
    speeds: list[float]


def write_stats(
    root: Path,
    tallies: Mapping[float, Tally],
    ranges: Mapping[float, tuple[float, float]] | None = None,
) -> list[str]:
    """Write both figures under ``root/stats`` and return their relative paths.

    Args:
        root: Dataset folder.
        tallies: Per-horizon counts and cue speeds.
        ranges: Per-horizon sampled speed range; histogram bins then span exactly it.
    """
    (root / "stats").mkdir(exist_ok=True)
    hs = sorted(tallies)
    # init.json rounds velocity components, so a speed may leave its range by up to ~1e-4 m/s
    padded = {h: (lo - 1e-3, hi + 1e-3) for h, (lo, hi) in (ranges or {}).items()}
    spans = [padded.get(h) for h in hs]
    speed_histograms(root / SPEED_HIST, hs, [tallies[h].speeds for h in hs], spans)
    collision_bars(
        root / COLLISIONS,
        hs,
        [tallies[h].collisions for h in hs],
        [tallies[h].scenes - tallies[h].collisions for h in hs],
    )
    return [SPEED_HIST, COLLISIONS]


def _save(fig: object, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)  # type: ignore[arg-type]
    fig.savefig(path, dpi=DPI, metadata={"Software": None})  # type: ignore[attr-defined]


COLUMN_WIDTH = 3.4
"""Inches: one column of a two-column paper, so the figure prints at its own size."""


def speed_histograms(
    path: Path,
    horizons: Sequence[float],
    speeds: Sequence[Sequence[float]],
    spans: Sequence[tuple[float, float] | None] | None = None,
) -> None:
    """One histogram of sampled cue speeds per horizon, stacked in one column (readable at
    one column width: 3.4 in wide, 7-9 pt text), each with its own speed axis."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    n = len(horizons)
    fig = Figure(figsize=(COLUMN_WIDTH, 0.55 + 1.05 * n), layout="constrained")
    axes = fig.subplots(n, 1, squeeze=False)[:, 0]
    spans = spans or [None] * n
    for ax, h, values, span in zip(axes, horizons, speeds, spans, strict=True):
        counts, _, _ = ax.hist(
            values, bins=BINS, range=span, color="#0072B2", edgecolor="white", linewidth=0.5
        )
        ax.set_ylim(0, 1.5 * max([*counts, 1]))  # room for the label above the tallest bar
        ax.text(
            0.99, 0.95, f"t = {h:g} s, n = {len(values)}", transform=ax.transAxes,
            ha="right", va="top", fontsize=8,
        )  # fmt: skip
        ax.tick_params(labelsize=7, pad=1)
        ax.yaxis.set_major_locator(MaxNLocator(integer=True, nbins=3))
        ax.set_ylabel("scenes", fontsize=7)
    axes[-1].set_xlabel("cue speed (m/s)", fontsize=8)
    fig.suptitle("Sampled cue-ball initial speeds", fontsize=9)
    _save(fig, path)


def collision_bars(
    path: Path, horizons: Sequence[float], hits: Sequence[int], misses: Sequence[int]
) -> None:
    """Grouped bars: scenes with and without a cue-ball collision, per horizon."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(max(4.0, 1.1 * len(horizons) + 2.0), 3.2), layout="constrained")
    ax = fig.subplots()
    xs = list(range(len(horizons)))
    width = 0.38
    left = ax.bar([x - width / 2 for x in xs], hits, width, label="collision", color="#c0392b")
    right = ax.bar(
        [x + width / 2 for x in xs], misses, width, label="no collision", color="#7f8c8d"
    )
    ax.bar_label(left, fontsize=8, padding=2)
    ax.bar_label(right, fontsize=8, padding=2)
    ax.set_xticks(xs, [f"{h:g} s" for h in horizons])
    ax.set_xlabel("horizon", fontsize=9)
    ax.set_ylabel("scenes", fontsize=9)
    ax.set_ylim(0, max([*hits, *misses, 1]) * 1.18)
    ax.legend(fontsize=8, frameon=False, loc="upper left", ncols=2)
    ax.set_title("Cue-ball collision vs no collision", fontsize=11)
    _save(fig, path)
