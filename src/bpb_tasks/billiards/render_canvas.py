"""The canvas shared by every scene image: geometry, the static table background, the palette.

The background (page, rails, cloth, grid, pockets, axes with ticks and labels) is drawn once per
process in RGB; :mod:`bpb_tasks.billiards.render_palette` turns it into the 8-bit palette image
that every scene image starts from.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

from PIL import Image, ImageDraw

from bpb_tasks.billiards import render_style as st
from bpb_tasks.billiards.config import HEADER_SPAN, DatasetConfig

TICK_MAJOR = 0.25  # metres between labelled ticks
TICK_MINOR = 0.05


@dataclass(frozen=True)
class CanvasSpec:
    """Canvas geometry in pixels; ``to_px`` maps table metres to pixel coordinates."""

    width_m: float
    height_m: float
    ppm: float
    left: int
    right: int
    top: int
    bottom: int
    radius_m: float
    pocket_radius_m: float
    pockets: tuple[tuple[float, float], ...]

    @classmethod
    def from_config(cls, config: DatasetConfig) -> CanvasSpec:
        """The canvas of ``config``'s table, pockets, ball radius and image settings."""
        im = config.image
        return cls(
            config.table.width,
            config.table.height,
            im.px_per_m,
            im.margin_left,
            im.margin_right,
            im.margin_top,
            im.margin_bottom,
            config.physics.ball_radius,
            config.pockets.radius,
            tuple(config.pockets.centers),
        )

    @property
    def size(self) -> tuple[int, int]:
        """Image size (width, height) in pixels."""
        w = self.left + round(self.width_m * self.ppm) + self.right
        return w, self.top + round(self.height_m * self.ppm) + self.bottom

    @property
    def header_right(self) -> int:
        """Where the header line ends: the table's right edge, or further right on a table
        narrower than the header (the margins make room, see ``config.needed_margins``)."""
        table_right = self.left + round(self.width_m * self.ppm)
        return max(table_right, self.left + math.ceil((HEADER_SPAN - 60) * self.scale))

    @property
    def radius_px(self) -> float:
        """Ball radius in pixels."""
        return self.radius_m * self.ppm

    @property
    def scale(self) -> float:
        """Font and stroke scale relative to the default 600 px per metre."""
        return self.ppm / 600.0

    def to_px(self, x: float, y: float) -> tuple[float, float]:
        """Pixel coordinates of table point ``(x, y)`` (y up on the table, down in the image)."""
        return self.left + x * self.ppm, self.top + (self.height_m - y) * self.ppm


def _ticks(limit: float, step: float) -> list[float]:
    return [i * step for i in range(math.floor(limit / step + 1e-9) + 1)]


@functools.cache
def background(spec: CanvasSpec) -> Image.Image:
    """The static table image (RGB); copy it before drawing on it."""
    img = Image.new("RGB", spec.size, st.PAGE)
    draw = ImageDraw.Draw(img)
    x0, y1 = spec.to_px(0, 0)
    x1, y0 = spec.to_px(spec.width_m, spec.height_m)
    rail = max(8, round(0.03 * spec.ppm))
    draw.rectangle((x0 - rail, y0 - rail, x1 + rail, y1 + rail), fill=st.RAIL)
    draw.rectangle((x0, y0, x1, y1), fill=st.CLOTH)
    for x in _ticks(spec.width_m, TICK_MAJOR)[1:-1]:
        px = spec.to_px(x, 0)[0]
        draw.line((px, y0, px, y1), fill=st.GRID, width=1)
    for y in _ticks(spec.height_m, TICK_MAJOR)[1:-1]:
        py = spec.to_px(0, y)[1]
        draw.line((x0, py, x1, py), fill=st.GRID, width=1)
    draw.rectangle((x0, y0, x1, y1), outline=st.CUSHION, width=max(2, rail // 5))
    _pockets(draw, spec)
    _axes(img, spec, max(rail, round(spec.pocket_radius_m * spec.ppm)) + round(6 * spec.scale))
    return img


def _pockets(draw: ImageDraw.ImageDraw, spec: CanvasSpec) -> None:
    r = spec.pocket_radius_m * spec.ppm
    for cx, cy in spec.pockets:
        px, py = spec.to_px(cx, cy)
        draw.ellipse((px - r, py - r, px + r, py + r), fill=st.POCKET)


def _axes(img: Image.Image, spec: CanvasSpec, offset: int) -> None:
    draw = ImageDraw.Draw(img)
    s = spec.scale
    label_font = st.font(round(15 * s))
    x0, y1 = spec.to_px(0, 0)
    x1 = spec.to_px(spec.width_m, 0)[0]
    draw.line((x0, y1 + offset, x1, y1 + offset), fill=st.INK, width=1)
    y0 = spec.to_px(0, spec.height_m)[1]
    draw.line((x0 - offset, y0, x0 - offset, y1), fill=st.INK, width=1)
    bottom, left = y1 + offset, x0 - offset
    for x in _ticks(spec.width_m, TICK_MINOR):
        px = spec.to_px(x, 0)[0]
        major = _is_major(x)
        draw.line((px, bottom, px, bottom + (9 if major else 4) * s), fill=st.INK, width=1)
        if major:
            draw.text((px, bottom + 11 * s), f"{x:g}", fill=st.INK, font=label_font, anchor="mt")
    for y in _ticks(spec.height_m, TICK_MINOR):
        py = spec.to_px(0, y)[1]
        major = _is_major(y)
        draw.line((left - (9 if major else 4) * s, py, left, py), fill=st.INK, width=1)
        if major:
            draw.text((left - 12 * s, py), f"{y:g}", fill=st.INK, font=label_font, anchor="rm")
    title_font = st.font(round(16 * s), bold=True)
    xmid = spec.to_px(spec.width_m / 2, 0)[0]
    draw.text((xmid, bottom + 36 * s), "x (m)", fill=st.INK, font=title_font, anchor="mt")
    ymid = spec.to_px(0, spec.height_m / 2)[1]
    _vertical_text(img, (left - 62 * s, ymid), "y (m)", title_font)


def _is_major(value: float) -> bool:
    ratio = value / TICK_MAJOR
    return abs(ratio - round(ratio)) < 1e-6


def _vertical_text(img: Image.Image, centre: tuple[float, float], text: str, font: st.Font) -> None:
    box = ImageDraw.Draw(img).textbbox((0, 0), text, font=font)
    w, h = int(box[2] - box[0] + 4), int(box[3] - box[1] + 6)
    patch = Image.new("RGB", (w, h), st.PAGE)
    ImageDraw.Draw(patch).text((w / 2, h / 2), text, fill=st.INK, font=font, anchor="mm")
    rotated = patch.rotate(90, expand=True)
    img.paste(
        rotated, (round(centre[0] - rotated.width / 2), round(centre[1] - rotated.height / 2))
    )


def draw_legend(img: Image.Image, spec: CanvasSpec) -> None:
    """The marker legend in the header of the trajectory image (drawn once, in RGB)."""
    draw = ImageDraw.Draw(img)
    s = spec.scale
    font = st.font(round(14 * s))
    y = spec.top / 2 - 14 * s  # the header line (render_palette.header_y)
    x = float(spec.header_right)
    items = (
        ("pocketed", "pocket"),
        ("wall contact", "wall"),
        ("ball contact", "ball"),
        ("faded: start", ""),
    )
    for text, kind in items:
        x -= draw.textlength(text, font=font)
        draw.text((x, y), text, fill=st.MUTED, font=font, anchor="lm")
        x -= 10 * s
        r = 7 * s
        if kind == "ball":
            draw.ellipse((x - 2 * r, y - r, x, y + r), outline=st.MARK_BALL, width=round(3 * s))
            x -= 2 * r
        elif kind == "wall":
            c = x - r
            diamond = [(c, y - r), (c + r, y), (c, y + r), (c - r, y)]
            draw.polygon(diamond, fill=st.MARK_WALL, outline=st.HALO)
            x -= 2 * r
        elif kind == "pocket":
            c = x - r
            for dx in (-r, r):
                draw.line(((c - dx, y - r), (c + dx, y + r)), fill=st.HALO, width=round(3 * s))
            x -= 2 * r
        x -= 24 * s
