"""Text patches in palette mode: antialiased text on a flat rectangle, mapped to the palette.

A patch is what drawing the text in RGB and mapping the result to the canvas's palette gives,
but made without either: on a flat background each pixel's colour depends only on the glyphs'
coverage there, so the coverage (FreeType's 8-bit mask, blended exactly as Pillow blends it)
goes through a 256-entry table of palette indices computed once per colour pair by that very
RGB blend and mapping. Patches are also kept for repeated texts ("no ball pocketed").
"""

from __future__ import annotations

import functools
import itertools
import math
import re
from typing import Any

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
    if outline is not None and w > 0 and h > 0:  # an empty patch (blank text, no pad) has none
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
    mask = _coverage(font, text)
    size = (mask.size[0] + 2 * pad, mask.size[1] + 2 * pad)
    coverage = Image.new("L", size, 0)
    coverage.im.paste(mask, (pad, pad, pad + mask.size[0], pad + mask.size[1]))
    indices = coverage._new(coverage.im.point(_table(spec, colour, back), None))  # no re-rounding
    patch = Image.frombytes("P", size, indices.tobytes())
    patch.putpalette(_palette_bytes(spec))
    return patch


TOKENS = re.compile(r"[0-9.]|[^0-9.]+")
"""Digits and points one by one, the text between them whole: the pieces glyph masks are kept
for (a scene's numbers change, its words do not)."""


def _coverage(font: ImageFont.FreeTypeFont, text: str) -> Any:
    """FreeType's coverage mask of ``text`` (an imaging core), put together from kept masks of
    its pieces (:data:`TOKENS`) where that is exact, else rendered whole.

    Pillow renders each glyph on its own at a whole pixel (where the pen, fraction included,
    rounds to) and blends it into the mask, clipped to the text's box. Pieces rendered from the
    same pen fractions land on the same pixels, so pasting them gives the same mask, provided
    the pieces advance the pen exactly as the whole text does (no kerning or shaping across
    them: checked against the whole text's advance) and no two pieces ink one column (where
    Pillow would blend them), pasting only their inked parts; otherwise the text is rendered
    whole.
    """
    pieces, x = [], 0.0
    for token in TOKENS.findall(text):
        pixel = math.floor(x)
        ink, left, top, advance = _piece(font, token, x - pixel)
        if ink is not None:
            pieces.append((ink, pixel + left, top))
        x += advance
    apart = all(a[1] + a[0].size[0] <= b[1] for a, b in itertools.pairwise(pieces))
    if not pieces or not apart or x != font.getlength(text):
        return font.getmask2(text, "L", start=(0.0, 0.0))[0]
    x0, y0, x1, y1 = (int(v) for v in font.getbbox(text))  # the whole mask's box
    out = Image.new("L", (x1 - x0, y1 - y0), 0).im
    for ink, left, top in pieces:
        a, b = max(left, x0), max(top, y0)  # the piece clipped to the box, as Pillow clips
        c, d = min(left + ink.size[0], x1), min(top + ink.size[1], y1)
        if a < c and b < d:
            part = ink.crop((a - left, b - top, c - left, d - top))
            out.paste(part, (a - x0, b - y0, c - x0, d - y0))
    return out


@functools.lru_cache(maxsize=4096)
def _piece(
    font: ImageFont.FreeTypeFont, token: str, fraction: float
) -> tuple[Any, int, int, float]:
    """The inked part of ``token``'s mask rendered from ``fraction`` of a pixel (``None``
    when blank), its offset, and the token's advance."""
    mask, (left, top) = font.getmask2(token, "L", start=(fraction, 0.0))
    box = mask.getbbox() if mask.size[0] and mask.size[1] else None
    if box is None:
        return None, left, top, font.getlength(token)
    return mask.crop(box), left + box[0], top + box[1], font.getlength(token)


@functools.cache
def _palette_bytes(spec: CanvasSpec) -> bytes:
    return bytes(palette_for(spec).image.getpalette() or [])


@functools.cache
def _table(spec: CanvasSpec, colour: st.RGB, back: st.RGB) -> tuple[int, ...]:
    """Palette index of ``colour`` drawn over ``back`` at each coverage value 0-255: Pillow's
    own blend of a 0-255 coverage ramp, mapped to the palette."""
    ramp = Image.frombytes("L", (256, 1), bytes(range(256)))
    rgb = Image.new("RGB", (256, 1), back)
    draw = ImageDraw.Draw(rgb)
    draw.draw.draw_bitmap((0, 0), ramp.im, draw._getink(colour)[0])
    return tuple(palette_for(spec).quantize(rgb).tobytes())


@functools.cache
def _index(spec: CanvasSpec, colour: st.RGB) -> int:
    """The palette index a flat ``colour`` is mapped to."""
    return palette_for(spec).quantize(Image.new("RGB", (1, 1), colour)).getpixel((0, 0))  # type: ignore[return-value]
