"""What ``bpb bench sim`` needs from the billiards family: its scenes and how outcomes differ.

The scenes come from a small self-contained sampler, deliberately independent of the dataset's
config (simulator tests use it too): centres uniform on the table, at least ``gap`` apart (and
from the walls), outside the pocket circles; only the cue ball moves, with a uniform direction
and a speed uniform in ``speeds``. Each scene's generator is seeded from ``(seed, index)``, so
any scene can be drawn alone.

An outcome is compared with the reference's by the final-position error (the worst ball on the
table in both) and by disagreements: whether the Q1 contacts, the Q2 walls and the pocketed set
differ, and how many balls the Q3 scorer would mark wrong.
"""

from __future__ import annotations

import math
import random
from collections.abc import Iterator

from bpb_tasks.billiards.scene.model import DEFAULT_POCKETS, DEFAULT_RADIUS, Scene
from bpb_tasks.billiards.truth.outcome import Outcome

CONTESTANTS = (
    "analytic",
    "pymunk:dt=0.01,tunnel=allow",
    "pymunk:dt=0.001,tunnel=allow",
    "pymunk:dt=0.0001,tunnel=allow",
)
"""Simulators compared by default: exact float64 and pymunk at three time steps, as it steps
(``tunnel=allow``: a coarse step is what is measured, not refused, and its error counts)."""

REFERENCE = "analytic:precision=50"
"""The reference: the analytic simulator in 50-digit mpmath arithmetic."""

DESCRIPTION = "random 7-ball scenes, only the cue ball moving at 0.1-1.2 m/s, horizons 1-5 s"
MEASURES = (
    "error = final-position distance in metres (per scene the worst ball on the table in both); "
    "q1, q2, pocketed = scenes whose Q1 contacts, Q2 walls or pocketed set differ; "
    "q3 = balls the Q3 scorer would mark wrong (more than R off, or pocketed in one run only)"
)


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


def random_scenes(
    count: int, seed: int = 0, *, speeds: tuple[float, float] = (0.1, 1.2)
) -> Iterator[Scene]:
    """``count`` scenes of the stream ``seed`` (``speeds`` as in :func:`random_scene`)."""
    for index in range(count):
        yield random_scene(seed, index, speeds=speeds)


def scaled_scene(scene: Scene, factor: float) -> Scene:
    """``scene`` with every velocity times ``factor``."""
    balls = [
        b.model_copy(update={"vel": (b.vel[0] * factor, b.vel[1] * factor)}) for b in scene.balls
    ]
    return scene.model_copy(update={"balls": balls})


def compare(outcome: Outcome, reference: Outcome, scene: Scene) -> dict[str, float]:
    """``error`` (m): the largest distance between final positions of balls on the table in
    both; the disagreement counts ``q1``, ``q2``, ``pocketed``; and ``q3``: the balls that Q3
    scoring would mark wrong (more than a ball radius off, or pocketed in one outcome only)."""
    from bpb_tasks.billiards.stability.annotation import labels

    ours, theirs = labels(outcome), labels(reference)
    q1, q2, pocketed = (float(a != b) for a, b in zip(ours, theirs, strict=True))
    error, q3 = 0.0, 0
    for ball, q in reference.positions.items():
        p = outcome.positions.get(ball)
        gap = math.dist(p, q) if p is not None and q is not None else None
        error = max(error, gap or 0.0)
        q3 += (p is None) != (q is None) or (gap is not None and gap > scene.physics.ball_radius)
    return {"error": error, "q1": q1, "q2": q2, "pocketed": pocketed, "q3": float(q3)}
