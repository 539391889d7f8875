"""The ``billiards`` scene family: random 7-ball scenes where only the cue ball moves.

Every scene's random stream comes from :func:`scene_rng` (a SHA-256 of seed, horizon and index),
so any scene can be regenerated alone and the same seed always gives the same scenes.
"""

from __future__ import annotations

import hashlib
import math
import random
from dataclasses import dataclass

from bpb_core.errors import BadInput
from bpb_core.layout import scene_id
from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.billiards.scene.model import Ball, Scene

MAX_TRIES_PER_BALL = 10_000


def scene_rng(seed: int, horizon: float, index: int) -> random.Random:
    """A generator seeded from a stable hash of ``(seed, horizon, index)`` (never global state)."""
    digest = hashlib.sha256(f"bpb-scene:{seed}:{horizon:g}:{index}".encode()).digest()
    return random.Random(int.from_bytes(digest[:16], "big"))


@dataclass(frozen=True)
class Draw:
    """The raw random choices behind one scene, before speeds are scaled to a range.

    Attributes:
        positions: Ball centres, cue ball first.
        angle: Cue direction in radians, uniform on [0, 2 pi).
        u: Uniform on [0, 1); the cue speed is ``low + u * (high - low)``.
    """

    positions: tuple[tuple[float, float], ...]
    angle: float
    u: float


def draw(rng: random.Random, config: DatasetConfig) -> Draw:
    """Draw cue direction, speed fraction and non-overlapping centres from ``rng``."""
    angle = rng.random() * 2.0 * math.pi
    u = rng.random()
    return Draw(_positions(rng, config), angle, u)


def build_scene(
    d: Draw, horizon: float, index: int, config: DatasetConfig, speed: float | None = None
) -> Scene:
    """The scene for draw ``d``; the cue speed comes from the horizon's range unless given."""
    if speed is None:
        rng = config.speed_range(horizon)
        speed = rng.low + d.u * (rng.high - rng.low)
    places = config.decimals
    vel = (round(speed * math.cos(d.angle), places) + 0.0, round(speed * math.sin(d.angle), places))
    balls = [
        Ball(id=i, pos=(round(x, places), round(y, places)), vel=vel if i == 0 else (0.0, 0.0))
        for i, (x, y) in enumerate(d.positions)
    ]
    return Scene(
        scene_id=scene_id(horizon, index),
        horizon=horizon,
        table=config.table,
        physics=config.physics,
        pockets=config.pockets,
        balls=balls,
    )


def _positions(rng: random.Random, config: DatasetConfig) -> tuple[tuple[float, float], ...]:
    radius = config.physics.ball_radius
    # Rounding to ``decimals`` moves a centre by up to half a unit per axis; keep that much slack.
    slack = 10.0**-config.decimals
    edge = radius + config.min_gap + slack
    x_hi, y_hi = config.table.width - edge, config.table.height - edge
    if x_hi <= edge or y_hi <= edge:
        raise BadInput("config: table: too small for one ball with the configured radius and gap")
    min_dist = 2 * radius + config.min_gap + 2 * slack
    pocket_dist = config.pockets.radius + config.pocket_margin + slack
    placed: list[tuple[float, float]] = []
    for _ in range(config.balls):
        for _ in range(MAX_TRIES_PER_BALL):
            p = (edge + rng.random() * (x_hi - edge), edge + rng.random() * (y_hi - edge))
            if _free(p, placed, min_dist) and _free(p, config.pockets.centers, pocket_dist):
                placed.append(p)
                break
        else:
            raise BadInput(
                f"config: balls: could not place ball {len(placed)} of {config.balls} clear of "
                "the other balls and the pockets; use fewer or smaller balls, a smaller min_gap, "
                "or smaller pockets (pockets.radius, pocket_margin)"
            )
    return tuple(placed)


def _free(p: tuple[float, float], others: list[tuple[float, float]], dist: float) -> bool:
    for q in others:  # a loop, not all() over a generator frame: a third of the draw's time
        if not math.dist(p, q) >= dist:
            break
    else:
        return True
    return False
