"""Text patches in palette mode: antialiased text on a flat rectangle, mapped to the palette.

A patch is what drawing the text in RGB and mapping the result to the canvas's palette gives,
but made without either: on a flat background each pixel's colour depends only on the glyphs'
coverage there, so the coverage (FreeType's 8-bit mask, blended exactly as Pillow blends it)
goes through a 256-entry table of palette indices computed once per colour pair by that very
RGB blend and mapping. Patches are also kept for repeated texts ("no ball pocketed").
"""

from __future__ import annotations

import functools

from PIL import Image, ImageDraw, ImageFont

from bpb_tasks.billiards import render_style as st
from bpb_tasks.billiards.render_canvas import CanvasSpec
from bpb_tasks.billiards.render_palette import palette_for


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
    """``text`` antialiased on a ``back`` rectangle (optionally outlined), in palette mode.

    The patch is shared between callers: paste or copy it, never draw on it.
    """
    if isinstance(font, ImageFont.FreeTypeFont) and pad >= 1:
        patch = _mapped_patch(spec, text, font, colour, back, pad)
        if outline is not None:
            w, h = patch.size
            ImageDraw.Draw(patch).rectangle(
                (0, 0, w - 1, h - 1), outline=_index(spec, outline), width=1
            )
        return patch
    left, top, right, bottom = font.getbbox(text)
    size = (int(right - left) + 2 * pad, int(bottom - top) + 2 * pad)
    return drawn_patch(spec, text, font, colour, back, size, (pad - left, pad - top), outline)


def drawn_patch(
    spec: CanvasSpec,
    text: str,
    font: st.Font,
    colour: st.RGB,
    back: st.RGB,
    size: tuple[int, int],
    at: tuple[float, float],
    outline: st.RGB | None,
) -> Image.Image:
    """The patch drawn in RGB at ``at`` and mapped to the palette (what the fast path makes)."""
    w, h = size
    patch = Image.new("RGB", size, back)
    draw = ImageDraw.Draw(patch)
    if outline is not None:
        draw.rectangle((0, 0, w - 1, h - 1), outline=outline, width=1)
    draw.text(at, text, fill=colour, font=font)
    return palette_for(spec).quantize(patch)


def _mapped_patch(
    spec: CanvasSpec,
    text: str,
    font: ImageFont.FreeTypeFont,
    colour: st.RGB,
    back: st.RGB,
    pad: int,
) -> Image.Image:
    """The patch from the glyph coverage and the colour pair's index table.

    FreeType's mask spans exactly the text's bounding box (``getbbox``), and its offset is the
    box's top-left corner, so drawing the text at ``(pad - left, pad - top)`` puts the mask at
    ``(pad, pad)``: inside the patch, off its one-pixel edge (where an outline goes).
    """
    mask, _ = font.getmask2(text, "L", start=(0.0, 0.0))
    size = (mask.size[0] + 2 * pad, mask.size[1] + 2 * pad)
    coverage = Image.new("L", size, 0)
    coverage.im.paste(mask, (pad, pad, pad + mask.size[0], pad + mask.size[1]))
    indices = coverage.point(_table(spec, colour, back))
    patch = Image.frombytes("P", size, indices.tobytes())
    patch.putpalette(palette_for(spec).image.getpalette() or [])
    return patch


@functools.cache
def _table(spec: CanvasSpec, colour: st.RGB, back: st.RGB) -> list[int]:
    """Palette index of ``colour`` drawn over ``back`` at each coverage value 0-255: Pillow's
    own blend of a 0-255 coverage ramp, mapped to the palette."""
    ramp = Image.frombytes("L", (256, 1), bytes(range(256)))
    rgb = Image.new("RGB", (256, 1), back)
    draw = ImageDraw.Draw(rgb)
    draw.draw.draw_bitmap((0, 0), ramp.im, draw._getink(colour)[0])
    return list(palette_for(spec).quantize(rgb).tobytes())


@functools.cache
def _index(spec: CanvasSpec, colour: st.RGB) -> int:
    """The palette index a flat ``colour`` is mapped to."""
    return palette_for(spec).quantize(Image.new("RGB", (1, 1), colour)).getpixel((0, 0))  # type: ignore[return-value]
