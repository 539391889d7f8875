"""The failure gallery draws on the dataset's own images at the right pixels."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from PIL import Image

from bpb_core.dataset import generate_dataset
from bpb_core.layout import SceneKey
from bpb_core.report.gallery import TRUTH_COLOUR, canvas_of, overlay
from bpb_core.results import load_results
from bpb_core.runner import run_eval
from bpb_tasks.billiards.config import DatasetConfig
from bpb_tasks.billiards.render_canvas import CanvasSpec


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("gallery")
    return Path(generate_dataset(root / "data", 1, [2.0], seed=3, workers=1))


def test_canvas_matches_the_renderer_geometry(dataset: Path) -> None:
    key = SceneKey(2.0, 0)
    with Image.open(key.dir(dataset) / "trajectory.png") as img:
        canvas = canvas_of(dataset, img)
    assert canvas is not None
    spec = CanvasSpec.from_config(DatasetConfig())
    for point in [(0.0, 0.0), (2.0, 1.0), (0.7, 0.3)]:
        assert canvas.to_px(*point) == pytest.approx(spec.to_px(*point))


def test_overlay_rings_the_true_final_positions(dataset: Path, tmp_path: Path) -> None:
    run_eval(dataset, "baseline:stasis", tmp_path / "baseline_stasis")
    units = load_results(tmp_path).units
    q3 = units[units["task"] == "q3"]
    png = overlay(dataset, SceneKey(2.0, 0), q3)
    with Image.open(io.BytesIO(png)) as img:
        rgb = img.convert("RGB")
    with Image.open(SceneKey(2.0, 0).dir(dataset) / "trajectory.png") as base:
        band = rgb.height - base.height
        canvas = canvas_of(dataset, base)
    assert canvas is not None and band > 0
    row = q3[q3["truth"] == "pos"].iloc[0]
    x, y = canvas.to_px(row["truth_x"], row["truth_y"])
    r = row["radius"] * canvas.ppm
    ring = [rgb.getpixel((round(x + dx), round(y + band))) for dx in (r - 1, r, -r, -(r - 1))]
    assert TRUTH_COLOUR in ring
