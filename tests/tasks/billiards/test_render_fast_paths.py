"""The renderer's shortcuts draw exactly what the plain definitions draw (same seed, same bytes).

Text patches are drawn as coverage and mapped through a palette-index table instead of drawing
in RGB and quantising; the arrow fit proves a shaft clear from its two ends instead of checking
every point; wall markers are drawn on a crop instead of the whole canvas. All must give the very
same pixels and lengths.
"""

from __future__ import annotations

import math

from hypothesis import example, given, settings, strategies as st
from PIL import Image, ImageDraw

from bpb_tasks.billiards.render import canvas as style
from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.render.images import ARROW_CLEARANCE, ARROW_MIN, arrow_length, wall_diamond
from bpb_tasks.billiards.render.palette import palette_for, text_patch
from bpb_tasks.billiards.scene.config import DatasetConfig

SPEC = CanvasSpec.from_config(DatasetConfig())
INKS = (style.INK, style.MUTED, style.ARROW, style.MARK_BALL, style.PAGE)
BACKS = (style.PAGE, style.CLOTH, style.POCKET)


@settings(max_examples=150, deadline=None)
@given(
    text=st.text(st.characters(codec="latin-1", exclude_categories=("Cc",)), min_size=1,
                 max_size=30),
    size=st.integers(8, 32), bold=st.booleans(), colour=st.sampled_from(INKS),
    back=st.sampled_from(BACKS), pad=st.integers(1, 8), outlined=st.booleans(),
)  # fmt: skip
@example(  # the speed label of a scene image
    text="0.86 m/s", size=17, bold=True, colour=style.INK, back=style.PAGE, pad=6, outlined=True
)
def test_a_text_patch_is_the_text_drawn_in_rgb_and_quantised(
    text: str, size: int, bold: bool, colour: style.RGB, back: style.RGB, pad: int, outlined: bool
) -> None:
    font = style.font(size, bold)
    outline = style.HALO if outlined else None
    left, top, right, bottom = font.getbbox(text)
    w, h = int(right - left) + 2 * pad, int(bottom - top) + 2 * pad
    rgb = Image.new("RGB", (w, h), back)
    draw = ImageDraw.Draw(rgb)
    if outline is not None:
        draw.rectangle((0, 0, w - 1, h - 1), outline=outline)
    draw.text((pad - left, pad - top), text, fill=colour, font=font)
    want = palette_for(SPEC).quantize(rgb)
    got = text_patch(SPEC, text, font, colour, back, pad, outline)
    assert got.mode == "P"
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
