"""Colours, fonts and ball sprites of the rendered scene images.

Ball sprites are drawn once per process with 4x supersampling (antialiased edges and numbers)
and pasted per scene; fonts are TrueType files read from disk (DejaVu from matplotlib's package
data or the system), falling back to Pillow's built-in font.
"""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path

from PIL import Image, ImageDraw, ImageFont

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


def _font_candidates(bold: bool) -> list[Path]:
    name = "DejaVuSans-Bold.ttf" if bold else "DejaVuSans.ttf"
    found: list[Path] = []
    spec = importlib.util.find_spec("matplotlib")  # locates the package without importing it
    if spec is not None and spec.origin:
        found.append(Path(spec.origin).parent / "mpl-data" / "fonts" / "ttf" / name)
    found.append(Path("/usr/share/fonts/truetype/dejavu") / name)
    return found


@functools.cache
def font(size: int, bold: bool = False) -> Font:
    """DejaVu Sans at ``size`` pixels, or Pillow's default font when no TTF is found."""
    for path in _font_candidates(bold):
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
