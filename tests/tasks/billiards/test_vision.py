"""Reading a scene back from its init.png and prompt (the perception of ``baseline:vision``)."""

from __future__ import annotations

import io
import math
from pathlib import Path

import pytest
from hypothesis import assume, given, settings, strategies as st
from PIL import Image

from bpb_core.interfaces import PromptOptions
from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.render.images import render_init
from bpb_tasks.billiards.render.png import encode_palette_png
from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.billiards.scene.model import Ball, Physics, Pockets, Scene, Table
from bpb_tasks.billiards.vision.frame import PerceptionFailed, read_prompt
from bpb_tasks.billiards.vision.perceive import perceive, perception_error
from bpb_tasks.questions.question import common_prompt

HALF_PIXEL_DIAGONAL_MM = 1000 * math.sqrt(0.5) / 600  # sprites are pasted at whole pixels


def _prompt(scene: Scene) -> str:
    return common_prompt(scene, PromptOptions("image", True, False, 0))


def _png(scene: Scene, **image: object) -> bytes:
    config = DatasetConfig.model_validate({"image": image} if image else {})
    return encode_palette_png(render_init(scene, CanvasSpec.from_config(config)), 1)


def _scenes(root: Path) -> list[Path]:
    return sorted(root.glob("h*/scene_*"))


def test_every_generated_scene_is_read_within_half_a_pixel(small_dataset: Path) -> None:
    for folder in _scenes(small_dataset):
        scene = Scene.model_validate_json((folder / "init.json").read_bytes())
        seen = perceive((folder / "init.png").read_bytes(), _prompt(scene))
        error = perception_error(seen, scene)
        assert error["centre_error_max_mm"] <= HALF_PIXEL_DIAGONAL_MM + 1e-6, folder
        assert error["speed_error_mps"] <= 0.0005 + 1e-9  # the header prints 3 decimals
        assert error["angle_error_deg"] < 1.0
        assert (seen.scene_id, seen.horizon, seen.physics) == (
            scene.scene_id,
            scene.horizon,
            scene.physics,
        )
        assert sorted(b.id for b in seen.balls) == sorted(b.id for b in scene.balls)


def test_touching_balls_are_read_as_a_valid_scene_at_another_scale() -> None:
    r = 0.028575
    balls = [
        Ball(id=0, pos=(0.5, 0.5), vel=(1.234, -0.4)),
        Ball(id=1, pos=(0.5 + 2 * r, 0.5)),  # touching the cue ball
        Ball(id=2, pos=(2.0 - r, 0.3)),  # touching the right wall
    ]
    scene = Scene(scene_id="h1_0000", horizon=1.0, balls=balls)
    seen = perceive(_png(scene, px_per_m=900.0), _prompt(scene))
    assert math.dist(seen.ball(0).pos, seen.ball(1).pos) >= 2 * r
    assert seen.ball(2).pos[0] <= 2.0 - r
    assert perception_error(seen, scene)["centre_error_max_mm"] < 1.0


def _cover(png: bytes, box: tuple[int, int, int, int], colour: tuple[int, int, int]) -> bytes:
    img = Image.open(io.BytesIO(png)).convert("RGB")
    img.paste(colour, box)
    out = io.BytesIO()
    img.save(out, format="PNG")
    return out.getvalue()


def test_what_cannot_be_read_is_named(small_dataset: Path) -> None:
    folder = _scenes(small_dataset)[0]
    scene = Scene.model_validate_json((folder / "init.json").read_bytes())
    png, prompt = (folder / "init.png").read_bytes(), _prompt(scene)
    with pytest.raises(PerceptionFailed, match="cannot be read"):
        perceive(b"not a png", prompt)
    with pytest.raises(PerceptionFailed, match="no axis"):
        perceive(_cover(png, (0, 0, 1400, 800), (255, 255, 255)), prompt)
    x, y = scene.ball(3).pos
    px, py = round(116 + 600 * x), round(84 + 600 * (1 - y))
    with pytest.raises(PerceptionFailed, match="ball 3"):
        perceive(_cover(png, (px - 20, py - 20, px + 21, py + 21), (34, 112, 70)), prompt)
    with pytest.raises(PerceptionFailed, match="ball radius"):
        perceive(png, prompt.replace("radius R =", "radius ="))


@settings(max_examples=60, deadline=None)
@given(
    width=st.floats(0.5, 4.0),
    height=st.floats(0.5, 2.0),
    radius=st.floats(0.005, 0.05),
    mu=st.floats(0.0, 0.5),
    g=st.floats(1.0, 20.0),
    restitution=st.floats(0.0, 1.0),
    pockets=st.lists(st.tuples(st.floats(0, 4), st.floats(0, 2)), max_size=6),
    horizon=st.floats(0.1, 30.0),
)
def test_the_prompt_states_every_fact_perception_needs(
    width: float,
    height: float,
    radius: float,
    mu: float,
    g: float,
    restitution: float,
    pockets: list[tuple[float, float]],
    horizon: float,
) -> None:
    centre = (width / 2, height / 2)
    assume(all(math.dist(centre, p) > 0.06 for p in pockets))  # a ball in a pocket is refused
    scene = Scene(
        scene_id="h2_0007",
        horizon=horizon,
        table=Table(width=width, height=height),
        physics=Physics(ball_radius=radius, mu=mu, g=g, wall_restitution=restitution),
        pockets=Pockets(radius=0.06 if pockets else 0.0, centers=pockets),
        balls=[Ball(id=0, pos=(width / 2, height / 2), vel=(1.0, 0.0))],
    )
    facts = read_prompt(_prompt(scene))
    close = {"rel_tol": 1e-5, "abs_tol": 1e-9}  # the prompt prints 6 significant digits
    assert (facts.scene_id, facts.ids) == ("h2_0007", (0,))
    assert math.isclose(facts.horizon, horizon, **close)
    assert math.isclose(facts.table.width, width, **close)
    assert math.isclose(facts.physics.ball_radius, radius, **close)
    assert math.isclose(facts.physics.mu, mu, **close)
    assert math.isclose(facts.physics.wall_restitution, restitution, **close)
    assert len(facts.pockets.centers) == len(pockets)
    for got, want in zip(facts.pockets.centers, pockets, strict=True):
        assert all(math.isclose(a, b, **close) for a, b in zip(got, want, strict=True))


def test_the_shortest_arrow_beside_a_ball_and_a_pocket_is_read() -> None:
    # a fast cue ball near the bottom-right corner, heading for the cushion: its arrow is cut to
    # the shortest length to stay on the cloth, beside ball 1 and the corner pocket
    balls = [Ball(id=0, pos=(1.88, 0.1), vel=(0.5, -2.95)), Ball(id=1, pos=(1.925, 0.032))]
    scene = Scene(scene_id="h1_0001", horizon=1.0, balls=balls)
    error = perception_error(perceive(_png(scene), _prompt(scene)), scene)
    # the arrow is kept on the cloth, here at its shortest (5 cm beyond the ball, 47 px from the
    # centre to the tip): such arrows read to 0.55 degrees median, 1.3 at the 90th percentile
    assert error["centre_error_mm"] < 2.0 and error["angle_error_deg"] < 1.5
    assert error["speed_error_mps"] <= 0.0005 + 1e-9
