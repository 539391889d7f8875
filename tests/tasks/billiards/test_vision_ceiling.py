"""The image's own ceiling: which labels survive moving every true centre to the pixel its ball is
drawn at (``baseline:vision`` stores it beside its perception error)."""

from __future__ import annotations

from bpb_core.capabilities import BoundsPerception
from bpb_core.interfaces import PromptOptions
from bpb_core.registry import Registry
from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.render.images import render_init
from bpb_tasks.billiards.render.png import encode_palette_png
from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.billiards.scene.model import Ball, Scene
from bpb_tasks.questions.question import common_prompt

PX = 1 / 600  # metres per pixel at the default image scale


def _ceiling(registry: Registry, offset_px: float) -> dict[str, bool]:
    # the cue ball runs along y = 0.5 (a whole pixel row) at ball 1, whose centre is
    # ``offset_px`` pixels above: they touch when the offset is under 2R = 34.29 px
    balls = [
        Ball(id=0, pos=(0.5, 0.5), vel=(1.0, 0.0)),
        Ball(id=1, pos=(0.9, 0.5 + offset_px * PX)),
        Ball(id=2, pos=(1.5, 0.2)),
    ]
    scene = Scene(scene_id="h1_0000", horizon=1.0, balls=balls)
    png = encode_palette_png(
        render_init(scene, CanvasSpec.from_config(DatasetConfig.model_validate({}))), 1
    )
    prompt = common_prompt(scene, PromptOptions("image", True, False, 0))
    family = registry.scene_family("billiards")
    assert isinstance(family, BoundsPerception)
    return family.perception_ceiling(png, prompt, scene, registry.simulator("analytic"))


def test_a_centre_on_a_whole_pixel_keeps_every_label(registry: Registry) -> None:
    assert _ceiling(registry, 34.0) == {"pixel_ceiling_q1_set": True, "pixel_ceiling_q2": True}


def test_a_near_miss_the_pixel_grid_turns_into_a_hit_is_beyond_any_reader(
    registry: Registry,
) -> None:
    # 34.4 px apart: no contact; drawn at 34 px, under 2R: a contact
    assert _ceiling(registry, 34.4)["pixel_ceiling_q1_set"] is False
    assert _ceiling(registry, 34.1)["pixel_ceiling_q1_set"] is True  # drawn at 34: still a hit
