"""A small self-contained sampler of random scenes for simulator tests and ``bpb bench sim``.

It is deliberately independent of the dataset's scene family: centres uniform on the table,
at least ``gap`` apart (and from the walls), outside the pocket circles; only the cue ball moves,
with a uniform direction and a speed uniform in ``speeds``. Each scene's generator is seeded from
``(seed, index)``, so any scene can be drawn alone.
"""

from __future__ import annotations

import math
import random
from collections.abc import Iterator

from bpb_tasks.billiards.scene import DEFAULT_POCKETS, DEFAULT_RADIUS, Scene


def random_scene(
    seed: int,
    index: int,
    *,
    balls: int = 7,
    horizons: tuple[int, ...] = (1, 2, 3, 4, 5),
    speeds: tuple[float, float] = (0.1, 1.2),
    gap: float = 1e-3,
) -> Scene:
    """Scene ``index`` of the stream ``seed`` (horizon drawn from ``horizons``)."""
    rng = random.Random(f"bench-scene:{seed}:{index}")
    radius = DEFAULT_RADIUS
    centres: list[tuple[float, float]] = []
    while len(centres) < balls:
        x = rng.uniform(radius + gap, 2.0 - radius - gap)
        y = rng.uniform(radius + gap, 1.0 - radius - gap)
        if all(math.dist((x, y), c) >= 2 * radius + gap for c in centres) and all(
            math.dist((x, y), p) > 0.06 for p in DEFAULT_POCKETS
        ):
            centres.append((x, y))
    angle = rng.uniform(0.0, 2 * math.pi)
    speed = rng.uniform(*speeds)
    cue = (speed * math.cos(angle), speed * math.sin(angle))
    return Scene.model_validate(
        {
            "scene_id": f"r{seed}_{index:05d}",
            "horizon": float(rng.choice(horizons)),
            "balls": [
                {"id": i, "pos": list(c), "vel": list(cue) if i == 0 else [0.0, 0.0]}
                for i, c in enumerate(centres)
            ],
        }
    )


def random_scenes(count: int, seed: int = 0, **options: object) -> Iterator[Scene]:
    """``count`` scenes of the stream ``seed`` (options as in :func:`random_scene`)."""
    for index in range(count):
        yield random_scene(seed, index, **options)  # type: ignore[arg-type]
