"""The dataset's ``stats/`` figures: cue-speed histograms and collision counts per horizon.

Drawn on Pillow (two simple charts do not need a plotting library, nor the import of one) on a
small chart canvas: a plot box with data limits, bars in data coordinates, a frame with outward
ticks, "nice" tick values (steps of 1, 2, 2.5 and 5 times a power of ten) and horizontal or
vertical text, all in DejaVu Sans (the font of the scene images). The files are saved without
metadata, so they are byte-identical across runs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np
from PIL import Image, ImageDraw

from bpb_tasks.billiards.render import canvas as st

SPEED_HIST = "stats/cue_speed_hist.png"
COLLISIONS = "stats/collisions.png"
BINS = 20
BLUE = (0, 114, 178)
RED = (192, 57, 43)
GREY = (127, 140, 141)


class Tally(Protocol):
    """Per-horizon counts (see :class:`bpb_tasks.billiards.family.BilliardsTally`)."""

    speed_range: tuple[float, float]
    scenes: int
    collisions: int
    speeds: list[float]


def write_stats(root: Path, tallies: Mapping[float, Tally]) -> list[str]:
    """Write both figures under ``root/stats`` (per horizon: counts, cue speeds and the sampled
    speed range, which the histogram's bins span) and return their relative paths."""
    (root / "stats").mkdir(exist_ok=True)
    hs = sorted(tallies)
    # init.json rounds velocity components, so a speed may leave its range by up to ~1e-4 m/s
    spans = [(tallies[h].speed_range[0] - 1e-3, tallies[h].speed_range[1] + 1e-3) for h in hs]
    speed_histograms(root / SPEED_HIST, hs, [tallies[h].speeds for h in hs], spans)
    collision_bars(
        root / COLLISIONS,
        hs,
        [tallies[h].collisions for h in hs],
        [tallies[h].scenes - tallies[h].collisions for h in hs],
    )
    return [SPEED_HIST, COLLISIONS]


COLUMN_WIDTH = 3.4
"""Inches: one column of a two-column paper, so the figure prints at its own size."""


def speed_histograms(
    path: Path,
    horizons: Sequence[float],
    speeds: Sequence[Sequence[float]],
    spans: Sequence[tuple[float, float]],
) -> None:
    """One histogram of sampled cue speeds per horizon, stacked in one column (readable at
    one column width: 3.4 in wide, 7-9 pt text), each with its own speed axis."""
    n = len(horizons)
    img, draw = new_chart(COLUMN_WIDTH, 0.55 + 1.05 * n)
    top, bottom, left, right = 44, 40, 70, img.width - 14
    pitch = (img.height - top - bottom) / max(n, 1)
    for k, (h, values, span) in enumerate(zip(horizons, speeds, spans, strict=True)):
        y0 = round(top + k * pitch)
        box = (left, y0, right, round(y0 + pitch) - 34)
        _histogram(img, draw, box, values, span, f"t = {h:g} s, n = {len(values)}")
    text(draw, (img.width / 2, 22), "Sampled cue-ball initial speeds", pt(9))
    text(draw, ((left + right) / 2, img.height - 14), "cue speed (m/s)", pt(8))
    img.save(path, format="PNG", optimize=False)


def _histogram(
    img: Image.Image,
    draw: ImageDraw.ImageDraw,
    box: tuple[int, int, int, int],
    values: Sequence[float],
    span: tuple[float, float],
    label: str,
) -> None:
    """One panel: ``BINS`` bars over ``span``, labelled ``label``."""
    counts, edges = np.histogram(np.asarray(values, dtype=float), bins=BINS, range=span)
    lo, hi = float(edges[0]), float(edges[-1])
    margin = (hi - lo) * 0.05
    top = 1.5 * max(int(counts.max(initial=0)), 1)  # room for the label above the tallest bar
    ax = Axes(*box, xlim=(lo - margin, hi + margin), ylim=(0.0, top))
    for count, a, b in zip(counts.tolist(), edges[:-1].tolist(), edges[1:].tolist(), strict=True):
        _, y0, x1, y1 = ax.bar(draw, a, b, count, BLUE)
        if count:
            draw.line((x1, y0, x1, y1), fill=st.PAGE, width=1)  # white edge between bars
    xs = nice_ticks(*ax.xlim, 9)
    ys = nice_ticks(0, top, 5, integer=True)
    size = pt(7)
    # tick labels with as few digits as the value needs (0.4, 2.5, 10)
    frame(draw, ax, [(x, f"{round(x, 6):g}") for x in xs], [(y, f"{y:g}") for y in ys], size)
    text(draw, (ax.x1 - 6, ax.y0 + 6), label, pt(8), anchor="rt")
    vertical_text(img, (14, (ax.y0 + ax.y1) / 2), "scenes", size)


def collision_bars(
    path: Path, horizons: Sequence[float], hits: Sequence[int], misses: Sequence[int]
) -> None:
    """Grouped bars: scenes with and without a cue-ball collision, per horizon."""
    n = len(horizons)
    img, draw = new_chart(max(4.0, 1.1 * n + 2.0), 3.2)
    width, top = 0.38, max([*hits, *misses, 1]) * 1.18
    margin = (n - 1 + 2 * width) * 0.05
    ax = Axes(
        86, 52, img.width - 16, img.height - 74,
        xlim=(-width - margin, n - 1 + width + margin), ylim=(0.0, top),
    )  # fmt: skip
    value_size = pt(8)
    for x, hit, miss in zip(range(n), hits, misses, strict=True):
        for left, count, colour in ((x - width, hit, RED), (x, miss, GREY)):
            x0, y0, x1, _ = ax.bar(draw, left, left + width, count, colour)
            text(draw, ((x0 + x1) / 2, y0 - 4), str(count), value_size, anchor="mb")
    ys = nice_ticks(0, top, 7, integer=True)
    xs = [(float(x), f"{h:g} s") for x, h in enumerate(horizons)]
    frame(draw, ax, xs, [(y, f"{y:g}") for y in ys], pt(9))
    lx: float = ax.x0 + 14  # the legend: the two bar kinds' swatches and names, from (lx, ly)
    ly = ax.y0 + 16
    for name, colour in (("collision", RED), ("no collision", GREY)):
        swatch = (lx, ly - value_size // 3, lx + 2 * value_size, ly + value_size // 3)
        draw.rectangle(swatch, fill=colour)
        text(draw, (lx + 2.6 * value_size, ly), name, value_size, anchor="lm")
        lx += 2.6 * value_size + st.font(value_size).getlength(name) + 2 * value_size
    text(draw, ((ax.x0 + ax.x1) / 2, 24), "Cue-ball collision vs no collision", pt(11))
    text(draw, ((ax.x0 + ax.x1) / 2, img.height - 20), "horizon", pt(9))
    vertical_text(img, (20, (ax.y0 + ax.y1) / 2), "scenes", pt(9))
    img.save(path, format="PNG", optimize=False)


DPI = 150
TICK = 7  # pixels: 3.5 pt outward ticks


def pt(points: float) -> int:
    """Pixels of ``points`` at :data:`DPI`."""
    return round(points * DPI / 72)


def nice_ticks(lo: float, hi: float, most: int, integer: bool = False) -> list[float]:
    """At most ``most`` evenly spaced round values in ``[lo, hi]`` (the finest step that fits)."""
    span = max(hi - lo, 1e-12)
    best: list[float] = [lo]
    for power in range(math.floor(math.log10(span)) + 1, math.floor(math.log10(span)) - 3, -1):
        for mantissa in (5.0, 2.5, 2.0, 1.0):
            step = mantissa * 10.0**power
            if integer and (step < 1 or step != round(step)):
                continue
            first = math.ceil(lo / step - 1e-9)
            ticks = [k * step for k in range(first, math.floor(hi / step + 1e-9) + 1)]
            if len(ticks) > most:
                return best
            best = ticks
    return best


@dataclass(frozen=True)
class Axes:
    """A plot box in pixels (``x0, y0`` top left, ``x1, y1`` bottom right) and its data limits."""

    x0: int
    y0: int
    x1: int
    y1: int
    xlim: tuple[float, float]
    ylim: tuple[float, float]

    def px(self, x: float, y: float) -> tuple[float, float]:
        """Pixel coordinates of data point ``(x, y)``."""
        (a, b), (c, d) = self.xlim, self.ylim
        return (
            self.x0 + (x - a) / (b - a) * (self.x1 - self.x0),
            self.y1 - (y - c) / (d - c) * (self.y1 - self.y0),
        )

    def bar(
        self, draw: ImageDraw.ImageDraw, left: float, right: float, top: float, fill: st.RGB
    ) -> tuple[float, float, float, float]:
        """A bar from 0 up to ``top`` between ``left`` and ``right``; its pixel box."""
        x0, y0 = self.px(left, top)
        x1, y1 = self.px(right, 0.0)
        box = (round(x0), round(y0), round(x1) - 1, round(y1) - 1)
        if top > 0:
            draw.rectangle(box, fill=fill)
        return box


def new_chart(width_in: float, height_in: float) -> tuple[Image.Image, ImageDraw.ImageDraw]:
    """A white RGB canvas of the given size in inches at :data:`DPI`."""
    img = Image.new("RGB", (round(width_in * DPI), round(height_in * DPI)), st.PAGE)
    return img, ImageDraw.Draw(img)


def frame(
    draw: ImageDraw.ImageDraw,
    ax: Axes,
    xticks: Sequence[tuple[float, str]],
    yticks: Sequence[tuple[float, str]],
    size: int,
) -> None:
    """The plot box's outline and its outward ticks with labels (``size`` pixel text)."""
    font = st.font(size)
    for x, label in xticks:
        px = round(ax.px(x, ax.ylim[0])[0])
        draw.line((px, ax.y1, px, ax.y1 + TICK), fill=st.INK, width=2)
        draw.text((px, ax.y1 + TICK + 3), label, fill=st.INK, font=font, anchor="mt")
    for y, label in yticks:
        py = round(ax.px(ax.xlim[0], y)[1])
        draw.line((ax.x0 - TICK, py, ax.x0, py), fill=st.INK, width=2)
        draw.text((ax.x0 - TICK - 4, py), label, fill=st.INK, font=font, anchor="rm")
    draw.rectangle((ax.x0, ax.y0, ax.x1, ax.y1), outline=st.INK, width=2)


def text(
    draw: ImageDraw.ImageDraw, at: tuple[float, float], words: str, size: int, anchor: str = "mm"
) -> None:
    """``words`` in ink at ``at`` (a Pillow text anchor such as ``mm`` or ``rt``)."""
    draw.text(at, words, fill=st.INK, font=st.font(size), anchor=anchor)


def vertical_text(img: Image.Image, centre: tuple[float, float], words: str, size: int) -> None:
    """``words`` reading bottom to top, centred on ``centre``."""
    font = st.font(size)
    left, top, right, bottom = font.getbbox(words)
    patch = Image.new("RGB", (int(right - left) + 4, int(bottom - top) + 4), st.PAGE)
    ImageDraw.Draw(patch).text((2 - left, 2 - top), words, fill=st.INK, font=font)
    turned = patch.rotate(90, expand=True)
    img.paste(turned, (round(centre[0] - turned.width / 2), round(centre[1] - turned.height / 2)))
