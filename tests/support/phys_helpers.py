"""Helpers shared by the physics tests: scene building and replaying an Outcome's segments."""

from __future__ import annotations

import math
from typing import Any

from bpb_tasks.billiards.scene.model import DEFAULT_RADIUS, Scene
from bpb_tasks.billiards.truth.outcome import Outcome, Segment

R = DEFAULT_RADIUS


def scene(
    balls: list[tuple[float, float, float, float]],
    *,
    horizon: float = 5.0,
    radius: float = R,
    mu: float = 0.002,
    g: float = 9.8,
    width: float = 2.0,
    height: float = 1.0,
    pockets: list[tuple[float, float]] | None = None,
    pocket_radius: float = 0.06,
) -> Scene:
    """A scene from ``(x, y, vx, vy)`` tuples, ids 0.. in order."""
    data: dict[str, Any] = {
        "scene_id": "test",
        "horizon": horizon,
        "table": {"width": width, "height": height},
        "physics": {"ball_radius": radius, "mu": mu, "g": g},
        "balls": [{"id": i, "pos": [b[0], b[1]], "vel": [b[2], b[3]]} for i, b in enumerate(balls)],
    }
    if pockets is not None:
        data["pockets"] = {"radius": pocket_radius, "centers": [list(p) for p in pockets]}
    return Scene.model_validate(data)


PRESSING_BREAK = (1.6857654904001647, 0.07649157715652259)
"""Cue velocity of the dataset card's pressing contact: after this :func:`rack` break (mu 0.002)
balls 5 and 6 overlap by 0.52 mm at t = 2.44 s."""


def rack(vel: tuple[float, float], *, cue_y: float = 0.5, mu: float = 0.002) -> Scene:
    """Ten touching balls in a triangle (apex at x = 1.3, y = 0.5), broken by the cue ball from
    (0.5, ``cue_y``) with velocity ``vel``; horizon 5 s, scene id ``rack``."""
    triangle = [
        (1.3 + row * math.sqrt(3) * R, 0.5 + (j - row / 2) * 2 * R)
        for row in range(4)
        for j in range(row + 1)
    ]
    cue = {"id": 0, "pos": [0.5, cue_y], "vel": list(vel)}
    return Scene.model_validate(
        {
            "scene_id": "rack",
            "horizon": 5.0,
            "physics": {"mu": mu},
            "balls": [cue, *({"id": i + 1, "pos": list(p)} for i, p in enumerate(triangle))],
        }
    )


def seg_state(seg: Segment, t: float) -> tuple[float, float, float, float]:
    """Position and velocity on ``seg`` at time ``t``."""
    speed = math.hypot(*seg.vel)
    if speed == 0:
        return seg.pos[0], seg.pos[1], 0.0, 0.0
    ux, uy = seg.vel[0] / speed, seg.vel[1] / speed
    tau = t - seg.t0
    if seg.decel > 0:
        tau = min(tau, speed / seg.decel)
    s = speed * tau - seg.decel * tau * tau / 2
    v = max(speed - seg.decel * tau, 0.0)
    return seg.pos[0] + ux * s, seg.pos[1] + uy * s, ux * v, uy * v


def state_at(outcome: Outcome, ball: int, t: float) -> tuple[float, float, float, float] | None:
    """State of ``ball`` at ``t`` (after any change at exactly ``t``); None once pocketed."""
    segs = outcome.segments[ball]
    if t > segs[-1].t1 and outcome.positions[ball] is None:
        return None
    current = segs[0]
    for seg in segs:
        if seg.t0 <= t:
            current = seg
    return seg_state(current, t)


def kinds(outcome: Outcome) -> list[tuple[str, tuple[int, ...], str | None]]:
    """The event log without times and positions."""
    return [(e.kind, e.ids, e.wall) for e in outcome.events if e.kind != "stop"]
