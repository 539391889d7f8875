"""The dataset's ``stats/`` figures: cue-speed histograms and collision counts per horizon.

Drawn on Pillow with :mod:`bpb_tasks.billiards.chart_canvas` (two simple charts do not need a
plotting library: importing matplotlib and laying out its figures took about 2 s of a fresh
``bpb generate``, these take milliseconds) and saved without metadata, so the files are
byte-identical across runs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Protocol

import numpy as np
from PIL import Image, ImageDraw

from bpb_tasks.billiards import chart_canvas as cc, render_style as st

SPEED_HIST = "stats/cue_speed_hist.png"
COLLISIONS = "stats/collisions.png"
BINS = 20
BLUE = (0, 114, 178)
RED = (192, 57, 43)
GREY = (127, 140, 141)


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


def _save(img: Image.Image, path: Path) -> None:
    img.save(path, format="PNG", optimize=False)


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
    n = len(horizons)
    img, draw = cc.new_chart(COLUMN_WIDTH, 0.55 + 1.05 * n)
    top, bottom, left, right = 44, 40, 70, img.width - 14
    pitch = (img.height - top - bottom) / max(n, 1)
    spans = spans or [None] * n
    for k, (h, values, span) in enumerate(zip(horizons, speeds, spans, strict=True)):
        y0 = round(top + k * pitch)
        box = (left, y0, right, round(y0 + pitch) - 34)
        _histogram(img, draw, box, values, span, f"t = {h:g} s, n = {len(values)}")
    cc.text(draw, (img.width / 2, 22), "Sampled cue-ball initial speeds", cc.pt(9))
    cc.text(draw, ((left + right) / 2, img.height - 14), "cue speed (m/s)", cc.pt(8))
    _save(img, path)


def _histogram(
    img: Image.Image,
    draw: ImageDraw.ImageDraw,
    box: tuple[int, int, int, int],
    values: Sequence[float],
    span: tuple[float, float] | None,
    label: str,
) -> None:
    """One panel: ``BINS`` bars over ``span`` (default: the values' range), labelled ``label``."""
    counts, edges = np.histogram(np.asarray(values, dtype=float), bins=BINS, range=span)
    lo, hi = float(edges[0]), float(edges[-1])
    margin = (hi - lo) * 0.05
    top = 1.5 * max(int(counts.max(initial=0)), 1)  # room for the label above the tallest bar
    ax = cc.Axes(*box, xlim=(lo - margin, hi + margin), ylim=(0.0, top))
    for count, a, b in zip(counts.tolist(), edges[:-1].tolist(), edges[1:].tolist(), strict=True):
        _, y0, x1, y1 = ax.bar(draw, a, b, count, BLUE)
        if count:
            draw.line((x1, y0, x1, y1), fill=st.PAGE, width=1)  # white edge between bars
    xs = cc.nice_ticks(*ax.xlim, 9)
    ys = cc.nice_ticks(0, top, 5, integer=True)
    size = cc.pt(7)
    cc.frame(draw, ax, [(x, cc.tick_text(x)) for x in xs], [(y, f"{y:g}") for y in ys], size)
    cc.text(draw, (ax.x1 - 6, ax.y0 + 6), label, cc.pt(8), anchor="rt")
    cc.vertical_text(img, (14, (ax.y0 + ax.y1) / 2), "scenes", size)


def collision_bars(
    path: Path, horizons: Sequence[float], hits: Sequence[int], misses: Sequence[int]
) -> None:
    """Grouped bars: scenes with and without a cue-ball collision, per horizon."""
    n = len(horizons)
    img, draw = cc.new_chart(max(4.0, 1.1 * n + 2.0), 3.2)
    width, top = 0.38, max([*hits, *misses, 1]) * 1.18
    margin = (n - 1 + 2 * width) * 0.05
    ax = cc.Axes(
        86, 52, img.width - 16, img.height - 74,
        xlim=(-width - margin, n - 1 + width + margin), ylim=(0.0, top),
    )  # fmt: skip
    value_size = cc.pt(8)
    for x, hit, miss in zip(range(n), hits, misses, strict=True):
        for left, count, colour in ((x - width, hit, RED), (x, miss, GREY)):
            x0, y0, x1, _ = ax.bar(draw, left, left + width, count, colour)
            cc.text(draw, ((x0 + x1) / 2, y0 - 4), str(count), value_size, anchor="mb")
    ys = cc.nice_ticks(0, top, 7, integer=True)
    xs = [(float(x), f"{h:g} s") for x, h in enumerate(horizons)]
    cc.frame(draw, ax, xs, [(y, f"{y:g}") for y in ys], cc.pt(9))
    _legend(draw, ax.x0 + 14, ax.y0 + 16, value_size)
    cc.text(draw, ((ax.x0 + ax.x1) / 2, 24), "Cue-ball collision vs no collision", cc.pt(11))
    cc.text(draw, ((ax.x0 + ax.x1) / 2, img.height - 20), "horizon", cc.pt(9))
    cc.vertical_text(img, (20, (ax.y0 + ax.y1) / 2), "scenes", cc.pt(9))
    _save(img, path)


def _legend(draw: ImageDraw.ImageDraw, x: float, y: float, size: int) -> None:
    """Colour swatches and names of the two bar kinds, side by side from ``(x, y)``."""
    for name, colour in (("collision", RED), ("no collision", GREY)):
        draw.rectangle((x, y - size // 3, x + 2 * size, y + size // 3), fill=colour)
        cc.text(draw, (x + 2.6 * size, y), name, size, anchor="lm")
        x += 2.6 * size + st.font(size).getlength(name) + 2 * size
