"""Rendered PNGs: they decode, share one canvas, and draw each ball where the scene puts it."""

from __future__ import annotations

import io
import math
import subprocess
import sys
from pathlib import Path

import pytest
from PIL import Image, ImageChops, ImageDraw

from bpb_core.dataset import load_dataset
from bpb_tasks.billiards.render import canvas as render_style
from bpb_tasks.billiards.render.canvas import CanvasSpec, background, ball_colour, draw_legend
from bpb_tasks.billiards.render.images import (
    render_final,
    render_init,
    render_pngs,
    render_trajectory,
)
from bpb_tasks.billiards.render.palette import FLAT, base, header_y, palette_for
from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.billiards.scene.model import Ball, Scene
from bpb_tasks.billiards.truth.outcome import Event, Outcome, Segment

BPB = str(Path(sys.executable).with_name("bpb"))
CONFIG = DatasetConfig()
SPEC = CanvasSpec.from_config(CONFIG)


def near(pixel: tuple[int, ...], colour: tuple[int, int, int], tol: int = 40) -> bool:
    return all(abs(a - b) <= tol for a, b in zip(pixel[:3], colour, strict=True))


def ring_pixel(img: Image.Image, pos: tuple[float, float]) -> tuple[int, ...]:
    """A pixel on the coloured ring of the ball centred at ``pos`` (outside its white badge)."""
    x, y = SPEC.to_px(*pos)
    return tuple(img.getpixel((round(x + 0.8 * SPEC.radius_px), round(y))))  # type: ignore[arg-type]


def test_images_decode_with_the_configured_canvas(small_dataset: Path) -> None:
    data = load_dataset(small_dataset)
    width = CONFIG.image.margin_left + 2 * 600 + CONFIG.image.margin_right
    height = CONFIG.image.margin_top + 600 + CONFIG.image.margin_bottom
    for key in data.keys:
        for name in ("init.png", "final.png", "trajectory.png"):
            with Image.open(data.path(key, name)) as img:
                img.load()
                assert img.format == "PNG" and img.size == (width, height) == SPEC.size


def test_init_image_draws_every_ball_at_its_position(small_dataset: Path) -> None:
    data = load_dataset(small_dataset)
    for key in data.keys:
        scene = data.scene(key)
        with Image.open(data.path(key, "init.png")) as img:
            rgb = img.convert("RGB")
        for ball in scene.balls[1:]:  # object balls: the cue arrow may cross the cue ball's ring
            assert near(ring_pixel(rgb, ball.pos), ball_colour(ball.id)), (key, ball.id)


def hand_scene() -> tuple[Scene, Outcome]:
    """Cue ball rolls right into ball 1 at rest; ball 1 is pocketed at the right middle."""
    scene = Scene(
        scene_id="h2_0000",
        horizon=2.0,
        pockets={"radius": 0.06, "centers": [[2.0, 0.5]]},
        balls=[Ball(id=0, pos=(0.5, 0.5), vel=(1.0, 0.0)), Ball(id=1, pos=(1.2, 0.5))],
    )
    a = 0.002 * 9.8
    t_hit = (1.0 - math.sqrt(1.0 - 2 * a * 0.64285)) / a
    segments = {
        0: (
            Segment(0.0, t_hit, (0.5, 0.5), (1.0, 0.0), a),
            Segment(t_hit, 2.0, (1.14285, 0.5), (0.0, 0.0), a),
        ),
        1: (
            Segment(0.0, t_hit, (1.2, 0.5), (0.0, 0.0), a),
            Segment(t_hit, 1.9, (1.2, 0.5), (1 - a * t_hit, 0.0), a),
        ),
    }
    events = (
        Event(t_hit, "ball", (0, 1), None, ((1.14285, 0.5), (1.2, 0.5))),
        Event(1.9, "pocket", (1,), None, ((1.94, 0.5),)),
    )
    return scene, Outcome(2.0, {0: (1.14285, 0.5), 1: None}, events, segments)


def test_final_and_trajectory_from_a_hand_made_outcome() -> None:
    scene, outcome = hand_scene()
    final = render_final(scene, outcome, SPEC).convert("RGB")
    assert near(ring_pixel(final, (1.14285, 0.5)), ball_colour(0))
    assert not near(ring_pixel(final, (1.2, 0.5)), ball_colour(1))  # pocketed: not drawn
    traj = render_trajectory(scene, outcome, SPEC).convert("RGB")
    x, y = SPEC.to_px(0.85, 0.5)  # on the cue ball's path, away from both balls
    assert near(tuple(traj.getpixel((round(x), round(y)))), ball_colour(0))  # type: ignore[arg-type]
    assert render_init(scene, SPEC).size == final.size == traj.size


def test_encoded_pngs_are_small_palette_images_and_deterministic() -> None:
    scene, outcome = hand_scene()
    first = render_pngs(scene, outcome, CONFIG)
    assert first == render_pngs(scene, outcome, CONFIG)
    for data in first.values():
        assert data.startswith(b"\x89PNG") and len(data) < 200_000
        assert Image.open(io.BytesIO(data)).mode == "P"


def _ink_box(path: Path) -> tuple[int, int, int, int]:
    """Distances (left, top, right, bottom) from the image's edges to its nearest drawn pixel."""
    with Image.open(path) as img:
        rgb = img.convert("RGB")
    page = Image.new("RGB", rgb.size, rgb.getpixel((0, 0)))  # type: ignore[arg-type]
    x0, y0, x1, y1 = ImageChops.difference(rgb, page).getbbox() or (0, 0, *rgb.size)
    return x0, y0, rgb.width - x1, rgb.height - y1


def _generate_one(config: Path, out: Path) -> Path:
    """``bpb generate`` of one scene at horizon 1 with ``config``; its dataset folder."""
    done = subprocess.run([BPB, "generate", "--out", str(out), "--config", str(config),
                           "--horizons", "1", "--per-horizon", "1", "--workers", "1"],
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return out


def test_labels_and_pockets_stay_on_larger_images(tmp_path: Path) -> None:
    """At px_per_m 800 the text is a third larger; margins left out grow with it (with the
    fixed 600-px margins the y and x axis labels and the right pockets were cut off)."""
    config = tmp_path / "big.toml"
    config.write_text("[image]\npx_per_m = 800\n[pockets]\nradius = 0.08\n")
    out = _generate_one(config, tmp_path / "ds")
    for name in ("init.png", "final.png", "trajectory.png"):
        assert min(_ink_box(out / "h1" / "scene_0000" / name)) >= 1, name


def _header_box(spec: CanvasSpec, header: str, legend: bool) -> tuple[int, int, int, int]:
    plain = base(spec).convert("RGB")
    drawn = base(spec, header, legend=legend).convert("RGB")
    box = ImageChops.difference(drawn, plain).getbbox()
    assert box is not None
    return box


@pytest.mark.parametrize("width", [1.0, 0.3, 2.0])
def test_the_header_title_and_legend_do_not_overlap_on_narrow_tables(width: float) -> None:
    """On a 1 m table the legend used to end at the table's edge, over the title."""
    config = DatasetConfig.model_validate({"table": {"width": width, "height": 1.0}})
    spec = CanvasSpec.from_config(config)
    title = _header_box(spec, "Trajectories, t = 0 to 12.5 s", legend=False)
    legend = _header_box(spec, "", legend=True)
    assert title[2] + 10 <= legend[0] and legend[2] <= spec.size[0]


@pytest.mark.parametrize(
    "image",
    [{}, {"px_per_m": 800}, {"px_per_m": 3000, "margin_top": 20}, {"px_per_m": 100}],
)
@pytest.mark.parametrize("header", ["", "State at t = 2.5 s", "Trajectories, t = 0 to 12.25 s"])
@pytest.mark.parametrize("legend", [False, True])
def test_the_header_is_what_drawing_the_whole_canvas_gives(
    image: dict[str, float], header: str, legend: bool
) -> None:
    """Only the header's band is drawn and mapped to the palette, over the mapped background:
    the pixels are those of the whole canvas drawn in RGB and mapped, as the dataset's images
    always were, on any canvas (a header near the top edge, larger and smaller text)."""
    spec = CanvasSpec.from_config(DatasetConfig.model_validate({"image": image}))
    whole = background(spec).copy()
    if header:
        font = render_style.font(round(19 * spec.scale), True)
        at = (spec.left - 60 * spec.scale, header_y(spec))
        ImageDraw.Draw(whole).text(at, header, fill=render_style.INK, font=font, anchor="lm")
    if legend:
        draw_legend(whole, spec)
    assert base(spec, header, legend).tobytes() == palette_for(spec).quantize(whole).tobytes()


def test_balls_under_a_pixel_across_are_drawn_without_error(tmp_path: Path) -> None:
    """A 1 mm ball is 0.6 px at 600 px per metre: its rim used to be drawn with a negative
    radius (internal error, exit 3)."""
    config = tmp_path / "specks.json"
    config.write_text('{"physics": {"ball_radius": 0.001}}')
    out = _generate_one(config, tmp_path / "ds")
    with Image.open(out / "h1" / "scene_0000" / "init.png") as img:
        assert img.size == SPEC.size


def test_the_palette_has_each_flat_colour_at_its_ink_and_a_fresh_process_computes_it() -> None:
    """Every process computes the palette itself: the images of workers must agree."""
    palette = palette_for(SPEC)
    colours = palette.image.getpalette() or []
    for rgb in FLAT:
        i = palette.ink(rgb)
        assert tuple(colours[3 * i : 3 * i + 3]) == rgb
    code = (
        "from bpb_tasks.billiards.scene.config import DatasetConfig\n"
        "from bpb_tasks.billiards.render.canvas import CanvasSpec\n"
        "from bpb_tasks.billiards.render.palette import palette_for\n"
        "print(bytes(palette_for(CanvasSpec.from_config(DatasetConfig())).image.getpalette()).hex())"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert bytes.fromhex(done.stdout.strip()) == bytes(colours)
