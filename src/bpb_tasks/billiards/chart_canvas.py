"""A small chart canvas on Pillow: a plot box with data limits, ticks, labels and text.

Enough for the dataset's two ``stats/`` figures (:mod:`bpb_tasks.billiards.stats_figures`):
bars in data coordinates, a frame with outward ticks, "nice" tick values (steps of 1, 2, 2.5
and 5 times a power of ten) and horizontal or vertical text, all in DejaVu Sans (the font of the
scene images). Drawing this way costs milliseconds and needs no plotting library to be imported.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from PIL import Image, ImageDraw

from bpb_tasks.billiards import render_style as st

DPI = 150
TICK = 7  # pixels: 3.5 pt outward ticks
Format = Callable[[float], str]


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


def tick_text(value: float) -> str:
    """A tick label: as few digits as the value needs (``0.4``, ``2.5``, ``10``)."""
    return f"{round(value, 6):g}"


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
