"""The billiards family's gallery picture maps table metres onto its own image, and the Q3
overlay rings the true final positions at the right pixels."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from PIL import Image

from bpb_core.dataset import generate_dataset
from bpb_core.layout import SceneKey
from bpb_core.registry import Registry
from bpb_core.results import load_results
from bpb_core.runner import run_eval
from bpb_tasks.billiards.family import BilliardsFamily
from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.q3.scorer import TRUTH_COLOUR, Q3Scorer


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("gallery")
    return Path(generate_dataset(root / "data", 1, [2.0], seed=3, workers=1))


def test_picture_matches_the_renderer_geometry(data: Path) -> None:
    key = SceneKey(2.0, 0)
    family = BilliardsFamily()
    picture = family.picture(data, key.dir(data), None)
    with Image.open(key.dir(data) / "trajectory.png") as img:
        assert picture.image.size == img.size
    spec = CanvasSpec.from_config(DatasetConfig())
    for point in [(0.0, 0.0), (2.0, 1.0), (0.7, 0.3)]:
        assert picture.to_px(*point) == pytest.approx(spec.to_px(*point))


def test_overlay_rings_the_true_final_positions(
    data: Path, tmp_path: Path, registry: Registry
) -> None:
    run_eval(data, "baseline:stasis", tmp_path / "baseline_stasis", registry=registry)
    units = load_results(tmp_path, registry=registry).units
    q3 = units[units["task"] == "q3"]
    key = SceneKey(2.0, 0)
    family = BilliardsFamily()
    picture = family.picture(data, key.dir(data), None)
    Q3Scorer().overlay(picture, q3)
    assert [e.label for e in picture.legend] == [
        "true final position",
        "predicted position",
        "error",
    ]
    with Image.open(io.BytesIO(picture.png())) as img:
        rgb = img.convert("RGB")
    with Image.open(key.dir(data) / "trajectory.png") as base:
        band = rgb.height - base.height
    assert band > 0
    row = q3[q3["truth"] == "pos"].iloc[0]
    x, y = picture.to_px(row["truth_x"], row["truth_y"])
    r = row["radius"] * picture.scale
    ring = [rgb.getpixel((round(x + dx), round(y + band))) for dx in (r - 1, r, -r, -(r - 1))]
    assert TRUTH_COLOUR in ring


def test_without_images_a_plain_table_is_drawn(tmp_path: Path) -> None:
    data = generate_dataset(tmp_path / "bare", 1, [1.0], seed=4, workers=1, images=False)
    key = SceneKey(1.0, 0)
    family = BilliardsFamily()
    scene = family.scene_model.model_validate_json((key.dir(data) / "init.json").read_bytes())
    picture = family.picture(data, key.dir(data), scene)
    cue = scene.ball(0)
    x, y = picture.to_px(*cue.pos)
    inside = round(x + 0.7 * scene.physics.ball_radius * picture.scale)  # clear of the label
    assert picture.image.getpixel((inside, round(y))) == (250, 250, 250)
