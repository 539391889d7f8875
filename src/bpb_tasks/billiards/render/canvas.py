"""The canvas shared by every scene image: geometry, colours, fonts, ball sprites and the static
table background.

Ball sprites are drawn once per process with 4x supersampling (antialiased edges and numbers)
and pasted per scene; fonts are TrueType files read from disk (DejaVu from matplotlib's package
data or the system), falling back to Pillow's built-in font. The background (page, rails, cloth,
grid, pockets, axes with ticks and labels) is drawn once per process in RGB;
:mod:`bpb_tasks.billiards.render.palette` turns it into the 8-bit palette image that every scene
image starts from.
"""

from __future__ import annotations

import functools
import importlib.util
import math
from dataclasses import dataclass
from pathlib import Path

from PIL import Image, ImageDraw, ImageFont

from bpb_tasks.billiards.scene.config import HEADER_SPAN, DatasetConfig

RGB = tuple[int, int, int]
Font = ImageFont.FreeTypeFont | ImageFont.ImageFont

PAGE: RGB = (255, 255, 255)
INK: RGB = (33, 33, 33)
MUTED: RGB = (110, 110, 110)
CLOTH: RGB = (34, 112, 70)
GRID: RGB = (52, 131, 88)
RAIL: RGB = (104, 66, 38)
CUSHION: RGB = (24, 84, 50)
POCKET: RGB = (18, 18, 18)
ARROW: RGB = (255, 214, 0)
HALO: RGB = (15, 15, 15)
MARK_BALL: RGB = (230, 30, 60)
MARK_WALL: RGB = (0, 190, 255)
MARK_POCKET: RGB = (255, 255, 255)

BALL_COLOURS: tuple[RGB, ...] = (
    (246, 244, 234),  # 0 cue ball
    (247, 196, 22),  # 1 yellow
    (32, 84, 205),  # 2 blue
    (214, 38, 38),  # 3 red
    (118, 52, 160),  # 4 purple
    (247, 128, 26),  # 5 orange
    (128, 28, 42),  # 6 maroon
    (24, 24, 24),  # 7 black
)
SUPERSAMPLE = 4


def ball_colour(ball_id: int) -> RGB:
    """Fill colour of ball ``ball_id``; ids past 7 reuse object-ball colours, never the cue's."""
    if ball_id == 0:
        return BALL_COLOURS[0]
    return BALL_COLOURS[1 + (ball_id - 1) % (len(BALL_COLOURS) - 1)]


@functools.cache
def font(size: int, bold: bool = False) -> Font:
    """DejaVu Sans at ``size`` pixels, or Pillow's default font when no TTF is found."""
    name = "DejaVuSans-Bold.ttf" if bold else "DejaVuSans.ttf"
    found = [Path("/usr/share/fonts/truetype/dejavu") / name]
    spec = importlib.util.find_spec("matplotlib")  # locates the package without importing it
    if spec is not None and spec.origin:
        found.insert(0, Path(spec.origin).parent / "mpl-data" / "fonts" / "ttf" / name)
    for path in found:
        if path.is_file():
            return ImageFont.truetype(str(path), size)
    return ImageFont.load_default(size)


@functools.cache
def ball_sprite(ball_id: int, radius_px: float, alpha: int = 255) -> Image.Image:
    """An RGBA sprite of ball ``ball_id``: coloured disc, dark rim, white badge with the id.

    The ball's centre is the centre of the sprite, whose side is odd. A faded sprite is the
    opaque one with its alpha scaled (not drawn again: the trajectory image fades every ball).
    """
    if alpha < 255:
        faded = ball_sprite(ball_id, radius_px).copy()  # the cached one stays opaque
        faded.putalpha(faded.getchannel("A").point(lambda a: a * alpha // 255))
        return faded
    side = int(2 * radius_px + 4) | 1
    big = side * SUPERSAMPLE
    r = radius_px * SUPERSAMPLE
    c = big / 2
    img = Image.new("RGBA", (big, big), (0, 0, 0, 0))
    draw = ImageDraw.Draw(img)
    rim = max(1.0, radius_px * 0.09) * SUPERSAMPLE
    draw.ellipse((c - r, c - r, c + r, c + r), fill=(*HALO, 255))
    inner = max(r - rim, 0.0)  # a ball under a pixel across is all rim
    draw.ellipse((c - inner, c - inner, c + inner, c + inner), fill=(*ball_colour(ball_id), 255))
    badge = r * 0.62
    if ball_id != 0:
        draw.ellipse((c - badge, c - badge, c + badge, c + badge), fill=(*PAGE, 255))
    label = font(max(1, round(r * (0.95 if ball_id < 10 else 0.72))), bold=True)
    draw.text((c, c + 0.04 * r), str(ball_id), fill=(*INK, 255), font=label, anchor="mm")
    return img.resize((side, side), Image.Resampling.LANCZOS)


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
    img = Image.new("RGB", spec.size, PAGE)
    draw = ImageDraw.Draw(img)
    x0, y1 = spec.to_px(0, 0)
    x1, y0 = spec.to_px(spec.width_m, spec.height_m)
    rail = max(8, round(0.03 * spec.ppm))
    draw.rectangle((x0 - rail, y0 - rail, x1 + rail, y1 + rail), fill=RAIL)
    draw.rectangle((x0, y0, x1, y1), fill=CLOTH)
    for x in _ticks(spec.width_m, TICK_MAJOR)[1:-1]:
        px = spec.to_px(x, 0)[0]
        draw.line((px, y0, px, y1), fill=GRID, width=1)
    for y in _ticks(spec.height_m, TICK_MAJOR)[1:-1]:
        py = spec.to_px(0, y)[1]
        draw.line((x0, py, x1, py), fill=GRID, width=1)
    draw.rectangle((x0, y0, x1, y1), outline=CUSHION, width=max(2, rail // 5))
    r = spec.pocket_radius_m * spec.ppm
    for cx, cy in spec.pockets:
        px, py = spec.to_px(cx, cy)
        draw.ellipse((px - r, py - r, px + r, py + r), fill=POCKET)
    _axes(img, spec, max(rail, round(spec.pocket_radius_m * spec.ppm)) + round(6 * spec.scale))
    return img


def _axes(img: Image.Image, spec: CanvasSpec, offset: int) -> None:
    draw = ImageDraw.Draw(img)
    s = spec.scale
    label_font = font(round(15 * s))
    x0, y1 = spec.to_px(0, 0)
    x1 = spec.to_px(spec.width_m, 0)[0]
    draw.line((x0, y1 + offset, x1, y1 + offset), fill=INK, width=1)
    y0 = spec.to_px(0, spec.height_m)[1]
    draw.line((x0 - offset, y0, x0 - offset, y1), fill=INK, width=1)
    bottom, left = y1 + offset, x0 - offset
    for x in _ticks(spec.width_m, TICK_MINOR):
        px = spec.to_px(x, 0)[0]
        major = _is_major(x)
        draw.line((px, bottom, px, bottom + (9 if major else 4) * s), fill=INK, width=1)
        if major:
            draw.text((px, bottom + 11 * s), f"{x:g}", fill=INK, font=label_font, anchor="mt")
    for y in _ticks(spec.height_m, TICK_MINOR):
        py = spec.to_px(0, y)[1]
        major = _is_major(y)
        draw.line((left - (9 if major else 4) * s, py, left, py), fill=INK, width=1)
        if major:
            draw.text((left - 12 * s, py), f"{y:g}", fill=INK, font=label_font, anchor="rm")
    title_font = font(round(16 * s), bold=True)
    xmid = spec.to_px(spec.width_m / 2, 0)[0]
    draw.text((xmid, bottom + 36 * s), "x (m)", fill=INK, font=title_font, anchor="mt")
    ymid = spec.to_px(0, spec.height_m / 2)[1]
    _vertical_text(img, (left - 62 * s, ymid), "y (m)", title_font)


def _is_major(value: float) -> bool:
    ratio = value / TICK_MAJOR
    return abs(ratio - round(ratio)) < 1e-6


def _vertical_text(img: Image.Image, centre: tuple[float, float], text: str, font: Font) -> None:
    box = ImageDraw.Draw(img).textbbox((0, 0), text, font=font)
    w, h = int(box[2] - box[0] + 4), int(box[3] - box[1] + 6)
    patch = Image.new("RGB", (w, h), PAGE)
    ImageDraw.Draw(patch).text((w / 2, h / 2), text, fill=INK, font=font, anchor="mm")
    rotated = patch.rotate(90, expand=True)
    img.paste(
        rotated, (round(centre[0] - rotated.width / 2), round(centre[1] - rotated.height / 2))
    )


def draw_legend(img: Image.Image, spec: CanvasSpec) -> None:
    """The marker legend in the header of the trajectory image (drawn once, in RGB)."""
    draw = ImageDraw.Draw(img)
    s = spec.scale
    face = font(round(14 * s))
    y = spec.top / 2 - 14 * s  # the header line (palette.header_y)
    x = float(spec.header_right)
    items = (
        ("pocketed", "pocket"),
        ("wall contact", "wall"),
        ("ball contact", "ball"),
        ("faded: start", ""),
    )
    for text, kind in items:
        x -= draw.textlength(text, font=face)
        draw.text((x, y), text, fill=MUTED, font=face, anchor="lm")
        x -= 10 * s
        r = 7 * s
        if kind == "ball":
            draw.ellipse((x - 2 * r, y - r, x, y + r), outline=MARK_BALL, width=round(3 * s))
            x -= 2 * r
        elif kind == "wall":
            c = x - r
            diamond = [(c, y - r), (c + r, y), (c, y + r), (c - r, y)]
            draw.polygon(diamond, fill=MARK_WALL, outline=HALO)
            x -= 2 * r
        elif kind == "pocket":
            c = x - r
            for dx in (-r, r):
                draw.line(((c - dx, y - r), (c + dx, y + r)), fill=HALO, width=round(3 * s))
            x -= 2 * r
        x -= 24 * s
