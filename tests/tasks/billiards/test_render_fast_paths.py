"""The renderer's shortcuts draw exactly what the plain definitions draw (same seed, same bytes).

Text patches are made from FreeType's coverage mask and a palette-index table instead of drawing
in RGB and quantising; the arrow fit proves a shaft clear from its two ends instead of checking
every point; wall markers are drawn on a crop instead of the whole canvas. All must give the very
same pixels and lengths.
"""

from __future__ import annotations

import math
from typing import Any

import pytest
from hypothesis import example, given, settings, strategies as st
from PIL import Image, ImageDraw, ImageFont

from bpb_tasks.billiards import render_style as style
from bpb_tasks.billiards.config import DatasetConfig
from bpb_tasks.billiards.render_arrow import ARROW_CLEARANCE, ARROW_MIN, arrow_length
from bpb_tasks.billiards.render_canvas import CanvasSpec
from bpb_tasks.billiards.render_text import _coverage, drawn_patch, text_patch
from bpb_tasks.billiards.render_trajectory import wall_diamond

SPEC = CanvasSpec.from_config(DatasetConfig())
INKS = (style.INK, style.MUTED, style.ARROW, style.MARK_BALL, style.PAGE)
BACKS = (style.PAGE, style.CLOTH, style.POCKET)


@settings(max_examples=150, deadline=None)
@given(
    text=st.text(st.characters(codec="latin-1", exclude_categories=("Cc",)), min_size=1,
                 max_size=30),
    size=st.integers(8, 32), bold=st.booleans(), colour=st.sampled_from(INKS),
    back=st.sampled_from(BACKS), pad=st.integers(0, 8), outlined=st.booleans(),
)  # fmt: skip
@example(  # blank text without padding: an empty patch, where Pillow refuses the outline
    text=" ", size=8, bold=False, colour=style.INK, back=style.PAGE, pad=0, outlined=True
)
def test_a_text_patch_is_the_text_drawn_in_rgb_and_quantised(
    text: str, size: int, bold: bool, colour: style.RGB, back: style.RGB, pad: int, outlined: bool
) -> None:
    font = style.font(size, bold)
    outline = style.HALO if outlined else None
    left, top, right, bottom = font.getbbox(text)
    box = (int(right - left) + 2 * pad, int(bottom - top) + 2 * pad)
    want = drawn_patch(SPEC, text, font, colour, back, box, (pad - left, pad - top), outline)
    got = text_patch(SPEC, text, font, colour, back, pad, outline)
    assert got.size == want.size
    assert got.tobytes() == want.tobytes()
    assert got.convert("RGB").tobytes() == want.convert("RGB").tobytes()


def _clear_everywhere(
    pos: tuple[float, float], direction: tuple[float, float], length: float
) -> bool:
    """The arrow's definition: every point every 5 mm on the cloth and off the pockets, the
    tip with the head's half-width and clearance to spare."""
    head = 10 * SPEC.scale / SPEC.ppm + ARROW_CLEARANCE
    r = SPEC.radius_m
    steps = max(2, math.ceil(length / 0.005))
    for k in range(steps + 1):
        d = r * 1.15 + (length + r - r * 1.15) * k / steps
        x, y = pos[0] + direction[0] * d, pos[1] + direction[1] * d
        room = head if k == steps else 0.0
        if not (room <= x <= SPEC.width_m - room and room <= y <= SPEC.height_m - room):
            return False
        if any(math.hypot(x - px, y - py) < SPEC.pocket_radius_m + room for px, py in SPEC.pockets):
            return False
    return True


def _longest(pos: tuple[float, float], direction: tuple[float, float], wanted: float) -> float:
    length = wanted
    while length > ARROW_MIN and not _clear_everywhere(pos, direction, length):
        length -= 0.005
    return max(length, ARROW_MIN)


@settings(max_examples=300, deadline=None)
@given(x=st.floats(-20, 220), y=st.floats(-20, 140), r=st.floats(0, 20), width=st.integers(1, 5))
@example(x=0.5, y=-3.5, r=7.0, width=2)  # cut by the canvas's top-left corner
def test_a_wall_marker_drawn_on_a_crop_is_the_polygon_drawn_on_the_canvas(
    x: float, y: float, r: float, width: int
) -> None:
    canvas = Image.new("P", (200, 120), 5)
    expected = canvas.copy()
    diamond = [(x, y - r), (x + r, y), (x, y + r), (x - r, y)]
    ImageDraw.Draw(expected).polygon(diamond, fill=3, outline=4, width=width)
    wall_diamond(canvas, (x, y), r, 3, 4, width)
    assert canvas.tobytes() == expected.tobytes()


@settings(max_examples=400, deadline=None)
@given(
    x=st.floats(-0.02, 2.02), y=st.floats(-0.02, 1.02), angle=st.floats(0, 2 * math.pi),
    wanted=st.floats(0.05, 0.5), axis=st.sampled_from([None, 0, 1, 2, 3]),
    pocket=st.sampled_from([None, 0, 1, 2, 3, 4, 5]),
)  # fmt: skip
def test_the_arrow_fit_is_the_per_point_definition(
    x: float, y: float, angle: float, wanted: float, axis: int | None, pocket: int | None
) -> None:
    pos = (x, y)
    if pocket is not None:  # within 0.2 m of a pocket, where the shaft may pass one closely
        px, py = SPEC.pockets[pocket]
        pos = (px + (x - 1.0) / 5, py + (y - 0.5) / 2.5)
    direction = (math.cos(angle), math.sin(angle))
    if axis is not None:  # exactly along a cushion: the shaft's ends share a coordinate
        direction = ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[axis]
    assert arrow_length(SPEC, pos, direction, wanted) == _longest(pos, direction, wanted)


@settings(max_examples=300, deadline=None)
@given(speed=st.floats(0, 20), pocketed=st.lists(st.integers(1, 15), max_size=6, unique=True))
def test_scene_texts_put_together_from_kept_pieces_are_the_whole_text(
    speed: float, pocketed: list[int]
) -> None:
    """The header notes and speed labels of scene images (numbers change, words do not) come
    from kept glyph pieces; their masks are FreeType's mask of the whole text."""
    texts = [
        (style.font(round(16 * SPEC.scale)), f"cue ball 0 speed {speed:.3f} m/s"),
        (style.font(round(17 * SPEC.scale), bold=True), f"{speed:.2f} m/s"),
        (style.font(round(16 * SPEC.scale)), f"pocketed: balls {', '.join(map(str, pocketed))}"),
    ]
    for font, text in texts:
        assert isinstance(font, ImageFont.FreeTypeFont)
        whole = font.getmask2(text, "L", start=(0.0, 0.0))[0]
        got = _coverage(font, text)
        assert got.size == whole.size
        assert bytes(got) == bytes(whole)


def test_scene_texts_are_put_together_from_pieces_not_rendered_whole(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The test above compares with the whole text's mask; this one checks the pieces are what
    made it (a fallback to rendering the whole text would pass the comparison trivially)."""
    font = style.font(round(16 * SPEC.scale))
    assert isinstance(font, ImageFont.FreeTypeFont)
    rendered: list[str] = []
    real = ImageFont.FreeTypeFont.getmask2

    def spy(self: ImageFont.FreeTypeFont, text: str, *args: Any, **kwargs: Any) -> Any:
        rendered.append(text)
        return real(self, text, *args, **kwargs)

    monkeypatch.setattr(ImageFont.FreeTypeFont, "getmask2", spy)
    for speed in (0.0, 1.234, 7.5, 19.999):
        text = f"cue ball 0 speed {speed:.3f} m/s"
        _coverage(font, text)
        assert text not in rendered


def test_a_scene_text_is_laid_out_from_its_pieces_without_measuring_it_whole(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Measuring a whole text (its advance, its box) costs as much as a layout: per scene it is
    done at most once for a new pen fraction of the last piece, never for each text."""
    measured: list[str] = []
    for name in ("getlength", "getbbox"):
        real = getattr(ImageFont.FreeTypeFont, name)

        def spy(self: ImageFont.FreeTypeFont, text: str, *a: Any, _real: Any = real,
                **k: Any) -> Any:  # fmt: skip
            measured.append(text)
            return _real(self, text, *a, **k)

        monkeypatch.setattr(ImageFont.FreeTypeFont, name, spy)
    font = style.font(round(16 * SPEC.scale))
    assert isinstance(font, ImageFont.FreeTypeFont)
    texts = [f"cue ball 0 speed {k / 997:.3f} m/s" for k in range(1, 3000, 7)]
    for text in texts:
        _coverage(font, text)
    wholes = [t for t in measured if t in texts]
    assert len(wholes) <= 64  # at most once per pen fraction of " m/s"
    for text in texts:  # once seen, never again
        _coverage(font, text)
    assert [t for t in measured if t in texts] == wholes


KERNED = "AFHOPRTVWYforvwy"  # letters DejaVu kerns before a point ("r.", "T.", ...)


@settings(max_examples=300, deadline=None)
@given(
    text=st.text(st.sampled_from(KERNED + "0123456789. ,:/msabl"), min_size=1, max_size=24),
    size=st.integers(8, 40), bold=st.booleans(),
)  # fmt: skip
@example(text="Vr.5 T.1", size=16, bold=False)
@example(text="1.5f.r.", size=17, bold=True)
def test_texts_with_kerned_boundaries_put_together_from_pieces_are_the_whole_text(
    text: str, size: int, bold: bool
) -> None:
    """Where neighbouring pieces kern (the whole text is laid out differently) or a piece's box
    is not known, the mask is still FreeType's mask of the whole text, at every canvas scale."""
    font = style.font(size, bold)
    assert isinstance(font, ImageFont.FreeTypeFont)
    whole = font.getmask2(text, "L", start=(0.0, 0.0))[0]
    got = _coverage(font, text)
    assert got.size == whole.size
    assert bytes(got) == bytes(whole)
