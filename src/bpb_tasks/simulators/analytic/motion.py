"""Ball motion under sliding friction, and the closed-form event times of a single ball.

A moving ball at ``p`` with speed ``v`` along unit direction ``u`` covers the distance
``s(t) = v t - a t^2 / 2`` (``a = mu g``) until it stops at ``t = v / a``, having covered
``v^2 / (2 a)``. Its path is a straight line, so wall, pocket and moving-vs-resting contact
times all come from a distance ``s`` along that line, turned into a time by the stable form
``t = 2 s / (v + sqrt(v^2 - 2 a s))``. Numbers are Python floats or mpmath values
(:mod:`bpb_tasks.simulators.analytic.numeric`); nothing here depends on which.

:func:`point_segment_gap2` is the compiled kernel's too: ``kernel_predict`` compiles this very
code with ``@jit``, so this module's source keys the kernel's cache folder as theirs do.
"""

from __future__ import annotations

from collections.abc import Callable

from bpb_tasks.simulators.analytic.numeric import Number


class Body:
    """The mutable state of one ball inside a simulation (not part of any public result).

    The ball was at ``(x, y)`` with speed ``speed`` along ``(ux, uy)`` at time ``t0``; it stops
    at ``tstop``. ``wall_t`` is the time of its next predicted wall contact and ``version``
    invalidates queued events when its motion changes.
    """

    __slots__ = (
        "alive",
        "id",
        "index",
        "seg",
        "speed",
        "t0",
        "tstop",
        "ux",
        "uy",
        "version",
        "wall_t",
        "x",
        "y",
    )

    def __init__(self, index: int, ball_id: int, x: Number, y: Number) -> None:
        self.index = index
        self.id = ball_id
        self.x = x
        self.y = y
        self.t0: Number = 0
        self.speed: Number = 0
        self.ux: Number = 0
        self.uy: Number = 0
        self.tstop: Number = 0
        self.wall_t: Number = 0
        self.version = 0
        self.alive = True
        self.seg: list[tuple[Number, Number, Number, Number, Number]] = []


class Motion:
    """Friction law shared by all balls: deceleration ``decel`` and the backend square root."""

    def __init__(self, decel: Number, sqrt: Callable[[Number], Number], inf: Number) -> None:
        self.decel = decel
        self.half = decel / 2
        self.sqrt = sqrt
        self.inf = inf

    def set_velocity(self, b: Body, t: Number, vx: Number, vy: Number) -> None:
        """Give ``b`` (already at its position at ``t``) the velocity ``(vx, vy)`` from ``t``."""
        b.t0 = t
        speed = self.sqrt(vx * vx + vy * vy)
        if speed > 0:
            b.speed, b.ux, b.uy = speed, vx / speed, vy / speed
            b.tstop = t + speed / self.decel if self.decel > 0 else self.inf
        else:
            b.speed, b.ux, b.uy, b.tstop = speed * 0, speed * 0, speed * 0, t

    def state(self, b: Body, t: Number) -> tuple[Number, Number, Number]:
        """Position and speed of ``b`` at ``t >= b.t0`` without changing it."""
        if b.speed == 0:
            return b.x, b.y, b.speed
        tau = (t if t < b.tstop else b.tstop) - b.t0
        s = b.speed * tau - self.half * tau * tau
        speed = b.speed - self.decel * tau if t < b.tstop else b.speed * 0
        return b.x + b.ux * s, b.y + b.uy * s, speed

    def advance(self, b: Body, t: Number) -> None:
        """Move ``b``'s reference point to ``t`` (its law of motion is unchanged)."""
        x, y, speed = self.state(b, t)
        b.x, b.y = x, y
        self.set_velocity(b, t, b.ux * speed, b.uy * speed)

    def time_for(self, speed: Number, s: Number) -> Number:
        """Time to cover ``s`` (less than the stopping distance) starting at ``speed``."""
        if self.decel == 0:
            return s / speed
        rest = speed * speed - 2 * self.decel * s
        return 2 * s / (speed + self.sqrt(rest if rest > 0 else rest * 0))


def line_contact(
    dx: Number,
    dy: Number,
    ux: Number,
    uy: Number,
    radius2: Number,
    sqrt: Callable[[Number], Number],
) -> Number | None:
    """Distance ``s >= 0`` along ``u`` from offset ``d`` (mover minus target) to the first point
    at distance ``sqrt(radius2)`` from the target while approaching; ``None`` if never.

    Starting inside the circle counts at ``s = 0`` only while moving inward; a tangent line
    (zero normal speed) does not count.
    """
    b = ux * dx + uy * dy
    c = dx * dx + dy * dy - radius2
    if c <= 0:
        return b * 0 if b < 0 else None
    if b >= 0:
        return None
    disc = b * b - c
    if disc <= 0:
        return None
    return c / (-b + sqrt(disc))


def point_segment_gap2(x: Number, y: Number, dx: Number, dy: Number) -> Number:
    """Squared distance from the origin to the segment from ``(x, y)`` to ``(x + dx, y + dy)``."""
    length2 = dx * dx + dy * dy
    if length2 > 0:
        k = -(x * dx + y * dy) / length2
        if k > 0:
            k = k if k < 1 else k * 0 + 1
            x, y = x + k * dx, y + k * dy
    return x * x + y * y
