"""The fixed 8-bit palette of a canvas, and the palette-mode pieces drawn from it.

Scene images are drawn directly in palette ("P") mode: copying a 1-byte-per-pixel base and
encoding it costs a third of RGB, and no per-image colour quantisation is needed. Ball sprites
are composed in RGB once, mapped to the palette, and pasted with a binary mask; text patches
(:mod:`bpb_tasks.billiards.render_text`) give the same pixels as text drawn in RGB and mapped
here. The palette holds every flat colour exactly, plus median-cut colours for the
antialiased edges; it depends only on the canvas, so it is identical in every process.

Computing it costs about 0.1 s of CPU in every process that draws (the sample image and its
median cut), so the default canvas's palette ships in ``render_palette.json``, stored with the
:func:`palette_key` of everything it was computed from; a process whose key differs (another
canvas, an edited style, other Pillow or font files) computes it. ``scripts/refresh_palette.py``
writes the file again.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import PIL
from PIL import Image, ImageChops, ImageDraw, ImageFont

from bpb_tasks.billiards import render_canvas, render_style as st
from bpb_tasks.billiards.render_canvas import CanvasSpec, background, draw_legend

FLAT: tuple[st.RGB, ...] = (
    st.PAGE, st.INK, st.MUTED, st.CLOTH, st.GRID, st.RAIL, st.CUSHION, st.POCKET, st.ARROW,
    st.HALO, st.MARK_BALL, st.MARK_WALL, st.MARK_POCKET, *st.BALL_COLOURS,
)  # fmt: skip
MAX_IDS = 16  # sprites of ids 0..15 shape the palette (the config allows up to 16 balls)
GHOST_ALPHA = 110
SHIPPED = Path(__file__).with_name("render_palette.json")


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
    """The canvas's palette (read from the shipped file when its key matches, else computed;
    once per process)."""
    flat = list(dict.fromkeys(FLAT))
    image = Image.new("P", (1, 1))
    image.putpalette(_shipped(spec) or computed_colours(spec))
    return Palette(image, {rgb: i for i, rgb in enumerate(flat)})


def computed_colours(spec: CanvasSpec) -> list[int]:
    """The palette's 768 channel values: the flat colours, then the sample's median cut."""
    flat = list(dict.fromkeys(FLAT))
    extra = _sample(spec).quantize(256 - len(flat), method=Image.Quantize.MEDIANCUT)
    colours = [c for rgb in flat for c in rgb] + (extra.getpalette() or [])[: 3 * (256 - len(flat))]
    return colours + [0] * (768 - len(colours))


def palette_key(spec: CanvasSpec) -> str:
    """A digest of what :func:`computed_colours` depends on: the canvas, the source of the
    modules that draw the sample (colours, sprites, background), the font files and the
    versions of Pillow and the libraries it draws text with."""
    digest = hashlib.sha256(repr(spec).encode())
    for source in (__file__, st.__file__, render_canvas.__file__):
        digest.update(Path(source or "").read_bytes())
    for bold in (False, True):
        font_path = getattr(st.font(17, bold), "path", None)
        digest.update(Path(font_path).read_bytes() if font_path else b"builtin font")
    core = ImageFont.core
    libraries = ("freetype2_version", "raqm_version", "harfbuzz_version", "fribidi_version")
    versions = [PIL.__version__, *(str(getattr(core, name, None)) for name in libraries)]
    digest.update(repr(versions).encode())
    return digest.hexdigest()


def _shipped(spec: CanvasSpec) -> list[int] | None:
    """The shipped palette if it was computed from exactly what ``spec`` would compute from."""
    try:
        stored = json.loads(SHIPPED.read_text())
        colours = list(bytes.fromhex(stored["colours"]))
        if len(colours) == 768 and stored["key"] == palette_key(spec):
            return colours
    except (OSError, ValueError, KeyError, TypeError, ImportError):
        pass  # no usable file (or no module source to key): computing gives the same palette
    return None


def ship(spec: CanvasSpec) -> None:
    """Write ``spec``'s computed palette and key as the shipped palette."""
    colours = bytes(computed_colours(spec)).hex()
    SHIPPED.write_text(json.dumps({"key": palette_key(spec), "colours": colours}) + "\n")


@functools.cache
def base(spec: CanvasSpec, header: str = "", legend: bool = False) -> Image.Image:
    """The background in palette mode with a fixed header (and the trajectory legend).

    Both are drawn in the header line at the top, so only the band of rows down to their lowest
    pixel is drawn (in RGB, at the same coordinates) and mapped, over the mapped background:
    mapping is pixel by pixel, so this is the image that drawing and mapping the whole canvas
    gives, at a tenth of the cost (each horizon has its own headers, made in every process)."""
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
