"""Ball sprites pasted by the fast path (core images kept per canvas, no per-call checks) are
exactly Image.paste of the sprite and its mask at the ball's pixel centre, clipped at the edges."""

from __future__ import annotations

from hypothesis import given, settings, strategies as st
from PIL import Image

from bpb_tasks.billiards.config import config_from_mapping
from bpb_tasks.billiards.render import paste_balls
from bpb_tasks.billiards.render_canvas import CanvasSpec
from bpb_tasks.billiards.render_palette import GHOST_ALPHA, base, stamp

SPECS = [
    CanvasSpec.from_config(config_from_mapping({"image": {"px_per_m": p}})) for p in (100, 600)
]
Balls = list[tuple[int, tuple[float, float]]]


def pasted_one_by_one(img: Image.Image, spec: CanvasSpec, balls: Balls, alpha: int) -> None:
    """The definition: each sprite pasted with its mask, centred on the ball."""
    for ball_id, pos in balls:
        sprite, mask = stamp(spec, ball_id, alpha)
        px, py = spec.to_px(*pos)
        half = sprite.width // 2
        img.paste(sprite, (round(px) - half, round(py) - half), mask)


@settings(max_examples=150, deadline=None)
@given(
    spec=st.sampled_from(SPECS),
    alpha=st.sampled_from([255, GHOST_ALPHA]),
    balls=st.lists(  # the table with a ball's width and more around it: edges and corners clip
        st.tuples(st.integers(0, 15), st.tuples(st.floats(-0.6, 2.6), st.floats(-0.6, 1.6))),
        max_size=20,
    ),
)
def test_pasted_balls_are_each_sprite_pasted_at_its_centre(
    spec: CanvasSpec, alpha: int, balls: Balls
) -> None:
    want = base(spec).copy()
    pasted_one_by_one(want, spec, balls, alpha)
    got = base(spec).copy()
    paste_balls(got, spec, balls, alpha)
    assert got.tobytes() == want.tobytes()
    rgb = base(spec).convert("RGB")  # not a palette image: Image.paste's own checks
    paste_balls(rgb, spec, balls, alpha)
    assert rgb.tobytes() == want.convert("RGB").tobytes()
