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
    patch = coverage._new(coverage.im.point(_table(spec, colour, back), None))  # no re-rounding
    patch.putpalette(_palette_bytes(spec))  # makes the "L" image of indices a "P" one in place
    return patch


TOKENS = re.compile(r"[0-9.]|[^0-9.]+")
"""Digits and points one by one, the text between them whole: the pieces glyph masks are kept
for (a scene's numbers change, its words do not)."""

_Box = tuple[int, int, int, int]
_Piece = tuple[Any, int, int]  # inked part of a token's mask, its left and top in the text's mask


def _coverage(font: ImageFont.FreeTypeFont, text: str) -> Any:
    """FreeType's coverage mask of ``text`` (an imaging core), put together from kept masks of
    its pieces (:data:`TOKENS`) where that is exact, else rendered whole.

    Pillow renders each glyph on its own at a whole pixel (where the pen, fraction included,
    rounds to) and blends it into the mask, clipped to the text's box. Pieces rendered from the
    same pen fractions land on the same pixels, so pasting them gives the same mask, provided
    the pieces lay out as in the whole text (ASCII in a font where each two neighbours
    :func:`_joins`), no two pieces ink one column (where Pillow would blend them), and the whole
    text's box follows from the pieces' (:func:`_box`); otherwise the text is rendered whole.
    """
    tokens = TOKENS.findall(text)
    if not text.isascii() or font.getname()[0] not in _FAMILIES:
        return _whole(font, text)
    if not all(_joins(font, a, b) for a, b in itertools.pairwise(tokens)):
        return _whole(font, text)
    pieces, starts, x = [], [], 0.0
    for token in tokens:
        starts.append(x)
        piece = _placed(font, token, x)
        if piece is not None:
            pieces.append(piece)
        x += _metrics(font, token)[0]
    apart = all(a[1] + a[0].size[0] <= b[1] for a, b in itertools.pairwise(pieces))
    box = _box(font, text, tokens, starts, x) if pieces and apart else None
    return _whole(font, text) if box is None else _pasted(pieces, box)


def _whole(font: ImageFont.FreeTypeFont, text: str) -> Any:
    return font.getmask2(text, "L", start=(0.0, 0.0))[0]


def _placed(font: ImageFont.FreeTypeFont, token: str, x: float) -> _Piece | None:
    """``token``'s inked piece with the pen at ``x`` (``None`` when blank)."""
    pixel = math.floor(x)
    ink, left, top = _piece(font, token, x - pixel)
    return None if ink is None else (ink, pixel + left, top)


def _pasted(pieces: list[_Piece], box: _Box) -> Any:
    """The pieces pasted into a mask spanning ``box``, each clipped to it as Pillow clips."""
    x0, y0, x1, y1 = box
    out = Image.new("L", (x1 - x0, y1 - y0), 0).im
    for ink, left, top in pieces:
        a, b = max(left, x0), max(top, y0)
        c, d = min(left + ink.size[0], x1), min(top + ink.size[1], y1)
        if a < c and b < d:
            part = ink.crop((a - left, b - top, c - left, d - top))
            out.paste(part, (a - x0, b - y0, c - x0, d - y0))
    return out


@functools.lru_cache(maxsize=4096)
def _joins(font: ImageFont.FreeTypeFont, a: str, b: str) -> bool:
    """Whether ``a`` then ``b`` (ASCII) advance the pen as ``a`` and ``b`` alone do.

    Why that is enough: the layout engine (raqm, i.e. HarfBuzz) can act across a boundary only
    by kerning, by substituting over a sequence crossing it, or by attaching a mark. DejaVu
    (:data:`_FAMILIES`, regular and bold) kerns by the first glyph's advance alone, which this
    check sees; none of its substitutions (f-ligatures, i and j before marks, ...) takes a digit
    or point, one of which is beside every :data:`TOKENS` boundary; ASCII has no marks.
    """
    return font.getlength(a + b) == _metrics(font, a)[0] + _metrics(font, b)[0]


_FAMILIES = frozenset({"DejaVu Sans"})
"""Fonts whose layout tables were read to make :func:`_joins` exact (kerning by advance only);
text in any other font is rendered whole."""


def _box(
    font: ImageFont.FreeTypeFont, text: str, tokens: list[str], starts: list[float], end: float
) -> _Box | None:
    """The whole text's box (FreeType's: glyph boxes and the pen line) from its tokens' boxes.

    A token's box depends on its pen fraction only by whole pixels: each glyph and pen end
    rounds to a pixel at most one further right than from a whole pixel, never left. So the
    left edge is the first token's when no later token's (as from a whole pixel) reaches past
    it, the top and bottom (no fraction on them) the extremes of all, and the right edge the
    last token's when no earlier token's, plus one, passes the pen's end. The last token's
    right edge from a fraction is learnt once from a whole text (:data:`_RIGHT`).
    """
    boxes = [_metrics(font, token)[1] for token in tokens]
    x0, pen_end = boxes[0][0], (round(end * 64) + 32) >> 6
    for start, (left, *_) in zip(starts[1:], boxes[1:], strict=True):
        if math.floor(start) + left < x0:
            return None
    for start, (*_, right, _) in zip(starts[:-1], boxes[:-1], strict=True):
        if math.floor(start) + right + (start % 1 > 0) > pen_end:
            return None
    pixel, fraction = math.floor(starts[-1]), starts[-1] % 1
    key = (font, tokens[-1], fraction)
    if fraction == 0:
        x1 = pixel + boxes[-1][2]
    elif key in _RIGHT:
        x1 = pixel + _RIGHT[key]
    else:
        x1 = int(font.getbbox(text)[2])
        if len(_RIGHT) < 4096:
            _RIGHT[key] = x1 - pixel
    return x0, min(b[1] for b in boxes), x1, max(b[3] for b in boxes)


_RIGHT: dict[tuple[ImageFont.FreeTypeFont, str, float], int] = {}
"""Right edges of last tokens from a pen fraction, relative to the pen's whole pixel."""


@functools.lru_cache(maxsize=4096)
def _metrics(font: ImageFont.FreeTypeFont, token: str) -> tuple[float, _Box]:
    """``token``'s advance and its box from a whole pixel."""
    box = font.getbbox(token)
    return font.getlength(token), (int(box[0]), int(box[1]), int(box[2]), int(box[3]))


@functools.lru_cache(maxsize=4096)
def _piece(font: ImageFont.FreeTypeFont, token: str, fraction: float) -> tuple[Any, int, int]:
    """The inked part of ``token``'s mask rendered from ``fraction`` of a pixel (``None``
    when blank) and its offset."""
    mask, (left, top) = font.getmask2(token, "L", start=(fraction, 0.0))
    box = mask.getbbox() if mask.size[0] and mask.size[1] else None
    if box is None:
        return None, left, top
    return mask.crop(box), left + box[0], top + box[1]


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
