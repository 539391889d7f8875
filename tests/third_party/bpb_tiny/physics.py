"""The ``slider-exact`` simulator: the puck's motion in closed form.

Unfold the track: the puck covers ``s(t) = v t - a t^2 / 2`` (``v = |v0|``, ``a = mu*g``) until
it stops at ``t_stop = v / a``, and the walls it meets lie at path distances ``d0, d0 + L,
d0 + 2L, ...`` (``d0`` is the distance to the wall it is heading for). A wall counts as hit when
the puck reaches it at or before the horizon while still moving (a puck that comes to rest
exactly at a wall touches it with zero speed: no hit); after the n-th hit the puck moves away
from that wall, so its position is read off the last wall it hit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bpb_tiny.scene import SliderScene

STABILITY_DT = 1e-3
"""Seconds by which the horizon is moved to decide stability."""


@dataclass(frozen=True)
class Outcome:
    """The state at ``horizon``: position, the times of the wall hits, still moving or not."""

    horizon: float
    x: float
    hit_times: tuple[float, ...]
    moving: bool

    @property
    def bounces(self) -> int:
        return len(self.hit_times)


def hit_time(v: float, a: float, d: float) -> float:
    """When path distance ``d`` is reached (``d < v^2 / 2a``), without cancellation."""
    return 2.0 * d / (v + math.sqrt(max(v * v - 2.0 * a * d, 0.0)))


def wall_hits(scene: SliderScene, travelled: float, stop: float) -> list[float]:
    """Path distances of the walls hit within ``travelled`` (stop distance ``stop``)."""
    first = scene.length - scene.x0 if scene.v0 > 0 else scene.x0
    hits: list[float] = []
    d = first
    while d <= travelled and d < stop:
        hits.append(d)
        d = first + len(hits) * scene.length
    return hits


def outcome(scene: SliderScene, horizon: float) -> Outcome:
    """Where the puck is at ``horizon`` and when it hit the walls."""
    v, a = abs(scene.v0), scene.mu_g
    if v == 0.0:
        return Outcome(horizon, scene.x0, (), False)
    t_stop, stop = v / a, v * v / (2.0 * a)
    moving = horizon < t_stop
    travelled = v * horizon - 0.5 * a * horizon * horizon if moving else stop
    hits = wall_hits(scene, travelled, stop)
    direction = 1.0 if scene.v0 > 0 else -1.0
    if not hits:
        x = scene.x0 + direction * travelled
    else:
        heading_right_first = direction > 0
        last_is_right = heading_right_first == (len(hits) % 2 == 1)
        wall = scene.length if last_is_right else 0.0
        x = wall + (-1.0 if last_is_right else 1.0) * (travelled - hits[-1])
    x = min(max(x, 0.0), scene.length)
    return Outcome(horizon, x, tuple(hit_time(v, a, d) for d in hits), moving)


class SliderExact:
    """Closed-form simulator of slider scenes (no options)."""

    name = "slider-exact"

    def run(self, scene: SliderScene, horizon: float | None = None) -> Outcome:
        """The outcome at ``horizon`` (default: the scene's own)."""
        return outcome(scene, scene.horizon if horizon is None else horizon)
