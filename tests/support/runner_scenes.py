"""Hand-made datasets for the runner tests: init.json, final.json (analytic truth), init.png."""

from __future__ import annotations

import io
import json
import math
import random
from pathlib import Path

from PIL import Image

from bpb_core.layout import scene_dir, scene_id
from bpb_core.registry import make_registry
from bpb_tasks.billiards.scene.model import Ball, Scene
from bpb_tasks.billiards.truth.final import final_state

RADIUS = 0.028575


def make_scene(horizon: float, index: int, seed: int = 0) -> Scene:
    """A valid 7-ball scene drawn from (seed, horizon, index)."""
    rng = random.Random(f"{seed}:{horizon}:{index}")
    balls: list[Ball] = []
    while len(balls) < 7:
        pos = (rng.uniform(0.1, 1.9), rng.uniform(0.1, 0.9))
        if any(math.dist(pos, b.pos) < 2 * RADIUS + 0.01 for b in balls):
            continue
        if any(math.dist(pos, c) < 0.1 for c in [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1)]):
            continue
        vel = (0.0, 0.0)
        if not balls:
            angle, speed = rng.uniform(0, 2 * math.pi), rng.uniform(0.2, 1.2)
            vel = (speed * math.cos(angle), speed * math.sin(angle))
        balls.append(Ball(id=len(balls), pos=pos, vel=vel))
    return Scene(scene_id=scene_id(horizon, index), horizon=horizon, balls=balls)


def png_bytes(seed: int, size: tuple[int, int] = (64, 32)) -> bytes:
    """A small real PNG whose pixels depend on ``seed``."""
    image = Image.new("RGB", size, (seed % 256, 120, 40))
    buffer = io.BytesIO()
    image.save(buffer, format="PNG")
    return buffer.getvalue()


def make_dataset(root: Path, horizons: tuple[float, ...] = (1.0, 3.0), per: int = 3) -> Path:
    """Write a dataset folder with ground truth from the analytic simulator."""
    sim = make_registry().simulator("analytic")
    for horizon in horizons:
        for index in range(per):
            scene = make_scene(horizon, index)
            folder = scene_dir(root, horizon, index)
            folder.mkdir(parents=True, exist_ok=True)
            (folder / "init.json").write_text(scene.model_dump_json(indent=1))
            final = final_state(scene, sim.run(scene))
            (folder / "final.json").write_text(final.model_dump_json(indent=1))
            (folder / "init.png").write_bytes(png_bytes(index + int(horizon) * 10))
    (root / "dataset.json").write_text(json.dumps({"dataset_hash": f"test-{len(horizons)}-{per}"}))
    return root
