"""The cue velocity arrow of init.png never runs over a rail or a pocket."""

from __future__ import annotations

import math

from hypothesis import given, settings, strategies as st

from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.render.images import ARROW_MIN, arrow_length
from bpb_tasks.billiards.scene.config import DatasetConfig

SPEC = CanvasSpec.from_config(DatasetConfig())


def _points(
    pos: tuple[float, float], direction: tuple[float, float], length: float
) -> list[tuple[float, float]]:
    r = SPEC.radius_m
    return [
        (pos[0] + direction[0] * d, pos[1] + direction[1] * d)
        for d in (r * 1.15 + (length + r - r * 1.15) * k / 50 for k in range(51))
    ]


@settings(max_examples=300, deadline=None)
@given(
    x=st.floats(0.0, 1.0), y=st.floats(0.0, 1.0), angle=st.floats(0, 2 * math.pi),
    speed=st.floats(0.05, 5.0),
)  # fmt: skip
def test_the_arrow_stays_on_the_cloth_and_off_the_pockets(
    x: float, y: float, angle: float, speed: float
) -> None:
    r = SPEC.radius_m
    pos = (r + x * (SPEC.width_m - 2 * r), r + y * (SPEC.height_m - 2 * r))
    clear = SPEC.pocket_radius_m + 0.01  # the sampler keeps centres this far from pockets
    if any(math.hypot(pos[0] - px, pos[1] - py) < clear + r for px, py in SPEC.pockets):
        return
    direction = (math.cos(angle), math.sin(angle))
    wanted = 0.10 + 0.12 * min(speed, 3.0)
    length = arrow_length(SPEC, pos, direction, wanted)
    assert ARROW_MIN <= length <= wanted
    if length == ARROW_MIN:
        return  # nothing longer fits (a ball against a cushion, heading into it)
    for px, py in _points(pos, direction, length):
        assert 0 <= px <= SPEC.width_m and 0 <= py <= SPEC.height_m
        for cx, cy in SPEC.pockets:
            assert math.hypot(px - cx, py - cy) >= SPEC.pocket_radius_m
