"""The fixed 8-bit palette of a canvas, and the palette-mode pieces drawn from it.

Scene images are drawn directly in palette ("P") mode: a page is a copy of a 1-byte-per-pixel
base, and no per-image colour quantisation is needed. Ball sprites
are composed in RGB once, mapped to the palette, and pasted with a binary mask; text patches
(:func:`text_patch`) give the same pixels as text drawn in RGB and mapped here. The palette
holds every flat colour exactly, plus median-cut colours for the antialiased edges; it depends
only on the canvas, so it is identical in every process, which computes it once.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

from PIL import Image, ImageChops, ImageDraw

from bpb_tasks.billiards.render import canvas as st
from bpb_tasks.billiards.render.canvas import CanvasSpec, background, draw_legend

FLAT: tuple[st.RGB, ...] = (
    st.PAGE, st.INK, st.MUTED, st.CLOTH, st.GRID, st.RAIL, st.CUSHION, st.POCKET, st.ARROW,
    st.HALO, st.MARK_BALL, st.MARK_WALL, st.MARK_POCKET, *st.BALL_COLOURS,
)  # fmt: skip
MAX_IDS = 16  # sprites of ids 0..15 shape the palette (the config allows up to 16 balls)
GHOST_ALPHA = 110


@dataclass(frozen=True, eq=False)
class Palette:
    """A 256-colour palette; ``ink`` gives the index of a flat colour for ImageDraw fills."""

    image: Image.Image
    index: dict[st.RGB, int] = field(default_factory=dict)

    def ink(self, colour: st.RGB) -> int:
        """Palette index of ``colour`` (one of :data:`FLAT`)."""
        return self.index[colour]

    def quantize(self, img: Image.Image) -> Image.Image:
        """``img`` (RGB) mapped to this palette, without dithering."""
        return img.quantize(palette=self.image, dither=Image.Dither.NONE)


def _sample(spec: CanvasSpec) -> Image.Image:
    """Background plus every sprite and some text: the colours images are made of."""
    base = background(spec)
    strip = Image.new("RGB", (base.width, 3 * int(2 * spec.radius_px + 8)), st.CLOTH)
    x, y = 2, 2
    for ball_id in range(MAX_IDS):
        for alpha in (255, GHOST_ALPHA):
            sprite = st.ball_sprite(ball_id, spec.radius_px, alpha)
            if x + sprite.width > strip.width:
                x, y = 2, y + sprite.height + 2
            strip.paste(sprite, (x, y), sprite)
            x += sprite.width + 2
    draw = ImageDraw.Draw(strip)
    draw.text((4, strip.height - 4), "0.123456789 m/s", fill=st.INK, font=st.font(17), anchor="ld")
    sample = Image.new("RGB", (base.width, base.height + strip.height))
    sample.paste(base, (0, 0))
    sample.paste(strip, (0, base.height))
    return sample


@functools.cache
def palette_for(spec: CanvasSpec) -> Palette:
    """The canvas's palette: the flat colours, then the median cut of a sample of what images
    are made of (once per process)."""
    flat = list(dict.fromkeys(FLAT))
    extra = _sample(spec).quantize(256 - len(flat), method=Image.Quantize.MEDIANCUT)
    colours = [c for rgb in flat for c in rgb] + (extra.getpalette() or [])[: 3 * (256 - len(flat))]
    image = Image.new("P", (1, 1))
    image.putpalette(colours + [0] * (768 - len(colours)))
    return Palette(image, {rgb: i for i, rgb in enumerate(flat)})


@functools.cache
def base(spec: CanvasSpec, header: str = "", legend: bool = False) -> Image.Image:
    """The background in palette mode with a fixed header (and the trajectory legend).

    Both are drawn in the header line at the top, so only the band of rows down to their lowest
    pixel is drawn (in RGB, at the same coordinates) and mapped, over the mapped background:
    mapping is pixel by pixel, so this is the image that drawing and mapping the whole canvas
    gives (each horizon has its own headers, made in every process)."""
    s = spec.scale
    font = st.font(round(19 * s), True)
    at = (spec.left - 60 * s, header_y(spec))
    rows = _legend_rows(spec) if legend else 0
    if header:  # the glyphs lie in their box, give or take a pixel of their subpixel start
        box = ImageDraw.Draw(background(spec)).textbbox(at, header, font=font, anchor="lm")
        rows = max(rows, math.ceil(box[3]) + 2)
    img = _mapped_background(spec).copy()
    rows = min(rows, img.height)
    if rows > 0:
        band = background(spec).crop((0, 0, img.width, rows))
        if header:
            ImageDraw.Draw(band).text(at, header, fill=st.INK, font=font, anchor="lm")
        if legend:
            draw_legend(band, spec)
        img.paste(palette_for(spec).quantize(band), (0, 0))
    return img


@functools.cache
def _mapped_background(spec: CanvasSpec) -> Image.Image:
    """The background in palette mode."""
    return palette_for(spec).quantize(background(spec))


@functools.cache
def _legend_rows(spec: CanvasSpec) -> int:
    """How many rows from the top hold the trajectory legend's pixels.

    The legend lies in the header line, so it is drawn and compared over the top margin only
    (84 of 780 rows by default; drawing clips at the band's edge and leaves the rows above as
    on the whole canvas); a legend reaching the band's last row is measured on the whole canvas.
    """
    width, height = spec.size
    for rows in (min(spec.top, height), height):
        plain = background(spec).crop((0, 0, width, rows))
        band = plain.copy()
        draw_legend(band, spec)
        box = ImageChops.difference(band, plain).getbbox()
        if box is None or box[3] < rows:
            break
    return 0 if box is None else box[3]


def header_y(spec: CanvasSpec) -> float:
    """Vertical centre of the header line."""
    return spec.top / 2 - 14 * spec.scale


@functools.cache
def stamp(spec: CanvasSpec, ball_id: int, alpha: int = 255) -> tuple[Image.Image, Image.Image]:
    """Ball sprite in palette mode (edges blended into the cloth) and its binary paste mask."""
    sprite = st.ball_sprite(ball_id, spec.radius_px, alpha)
    flat = Image.new("RGB", sprite.size, st.CLOTH)
    flat.paste(sprite, (0, 0), sprite)
    mask = sprite.getchannel("A").point(lambda a: 255 if a >= 24 else 0)
    return palette_for(spec).quantize(flat), mask


@functools.lru_cache(maxsize=1024)
def text_patch(
    spec: CanvasSpec,
    text: str,
    font: st.Font,
    colour: st.RGB,
    back: st.RGB,
    pad: int = 2,
    outline: st.RGB | None = None,
) -> Image.Image:
    """``text`` antialiased on a ``back`` rectangle ``pad`` pixels around the text's box
    (optionally outlined on its edge, over the text when ``pad`` is 0), in palette mode: the
    pixels that drawing it in RGB and mapping the result to the palette gives.

    On a flat background each pixel's colour depends only on the glyphs' coverage there, so the
    text is drawn as coverage (an "L" image) and each coverage value mapped through a table made
    by that very RGB drawing and mapping (:func:`_table`). The patch is shared between callers:
    paste or copy it, never draw on it.
    """
    left, top, right, bottom = font.getbbox(text)
    w, h = int(right - left) + 2 * pad, int(bottom - top) + 2 * pad
    coverage = Image.new("L", (w, h), 0)
    ImageDraw.Draw(coverage).text((pad - left, pad - top), text, fill=255, font=font)
    patch = coverage.point(_table(spec, colour, back))
    patch.putpalette(palette_for(spec).image.getpalette() or [])  # the "L" image becomes "P"
    if outline is not None and w > 0 and h > 0:  # an empty patch (blank text, no pad) has none
        ImageDraw.Draw(patch).rectangle((0, 0, w - 1, h - 1), outline=_index(spec, outline))
    return patch


@functools.cache
def _table(spec: CanvasSpec, colour: st.RGB, back: st.RGB) -> tuple[int, ...]:
    """Palette index of ``colour`` drawn over ``back`` at each coverage value 0-255: a 0-255
    coverage ramp drawn in RGB as Pillow draws text (``ImageDraw.bitmap``), mapped."""
    ramp = Image.frombytes("L", (256, 1), bytes(range(256)))
    rgb = Image.new("RGB", (256, 1), back)
    ImageDraw.Draw(rgb).bitmap((0, 0), ramp, fill=colour)
    return tuple(palette_for(spec).quantize(rgb).tobytes())


@functools.cache
def _index(spec: CanvasSpec, colour: st.RGB) -> int:
    """The palette index a flat ``colour`` is mapped to."""
    return palette_for(spec).quantize(Image.new("RGB", (1, 1), colour)).getpixel((0, 0))  # type: ignore[return-value]
