"""Ball motion under sliding friction, and the closed-form event times of a single ball.

A moving ball at ``p`` with speed ``v`` along unit direction ``u`` covers the distance
``s(t) = v t - a t^2 / 2`` (``a = mu g``) until it stops at ``t = v / a``, having covered
``v^2 / (2 a)``. Its path is a straight line, so wall, pocket and moving-vs-resting contact
times all come from a distance ``s`` along that line, turned into a time by the stable form
``t = 2 s / (v + sqrt(v^2 - 2 a s))``. Numbers are Python floats or mpmath values
(:class:`~bpb_tasks.simulators.analytic.engine.Numeric`); nothing here depends on which.

The functions after :class:`Motion` are the compiled kernel's too: it compiles this very code
with ``@jit`` (:mod:`~bpb_tasks.simulators.analytic.kernel`), so this module's source
keys the kernel's cache folder as theirs do, and both engines compute the same numbers.
"""

from __future__ import annotations

import math
from typing import Any

from bpb_tasks.simulators.analytic.roots import NO_ROOT, Number, first_contact, sqrt


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
    """Friction law shared by all balls: deceleration ``decel``."""

    def __init__(self, decel: Number) -> None:
        self.decel = decel
        self.half = decel / 2

    def set_velocity(self, b: Body, t: Number, vx: Number, vy: Number) -> None:
        """Give ``b`` (already at its position at ``t``) the velocity ``(vx, vy)`` from ``t``."""
        b.t0 = t
        b.speed, b.ux, b.uy, b.tstop = heading(t, vx, vy, self.decel)

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


def heading(t: Number, vx: Number, vy: Number, decel: Number) -> tuple[Number, ...]:
    """Speed, unit direction and stopping time (infinite without friction) of a ball given the
    velocity ``(vx, vy)`` at ``t``."""
    speed = sqrt(vx * vx + vy * vy)
    if speed > 0:
        return speed, vx / speed, vy / speed, t + speed / decel if decel > 0 else math.inf
    return speed * 0, speed * 0, speed * 0, t


def time_for(decel: Number, speed: Number, s: Number) -> Number:
    """Time to cover ``s`` (less than the stopping distance) starting at ``speed``."""
    if decel == 0:
        return s / speed
    rest = speed * speed - 2 * decel * s
    return 2 * s / (speed + sqrt(rest if rest > 0 else rest * 0))


def line_contact(dx: Number, dy: Number, ux: Number, uy: Number, radius2: Number) -> Number:
    """Distance ``s >= 0`` along ``u`` from offset ``d`` (mover minus target) to the first point
    at distance ``sqrt(radius2)`` from the target while approaching; :data:`NO_ROOT` if never.

    Starting inside the circle counts at ``s = 0`` only while moving inward; a tangent line
    (zero normal speed) does not count.
    """
    b = ux * dx + uy * dy
    c = dx * dx + dy * dy - radius2
    if c <= 0:
        return b * 0 if b < 0 else NO_ROOT
    if b >= 0:
        return NO_ROOT
    disc = b * b - c
    if disc <= 0:
        return NO_ROOT
    return c / (-b + sqrt(disc))


def pocket_entry(
    x: Number, y: Number, ux: Number, uy: Number, pockets: Any, r: Number, reach: Number
) -> tuple[Number, int]:
    """The distance along ``u`` from ``(x, y)`` at which the centre first enters one of the
    ``pockets`` (centres; radius ``r``, tangency counts) within ``reach``, and that pocket's
    index; :data:`NO_ROOT` and 0 if none."""
    best, pocket, r2 = NO_ROOT, 0, r * r
    for k in range(len(pockets)):
        dx, dy = x - pockets[k][0], y - pockets[k][1]
        along = ux * dx + uy * dy
        if along >= 0:  # moving away: only a centre already inside counts
            if not (-r <= dx <= r and -r <= dy <= r and dx * dx + dy * dy <= r2):
                continue
            s = along * 0
        else:
            c = dx * dx + dy * dy - r2
            if c <= 0:
                s = c * 0  # already inside
            elif along * along < c:
                continue  # the line passes outside the circle
            else:
                s = c / (-along + sqrt(along * along - c))
        if s <= reach and (best == NO_ROOT or s < best):
            best, pocket = s, k
    return best, pocket


def pocket_holding(x: Number, y: Number, pockets: Any, r: Number) -> int:
    """The index of the first of the ``pockets`` (radius ``r``) whose circle holds ``(x, y)``,
    or -1."""
    r2 = r * r
    for k in range(len(pockets)):
        dx, dy = x - pockets[k][0], y - pockets[k][1]
        if -r <= dx <= r and dx * dx + dy * dy <= r2:
            return k
    return -1


def point_segment_gap2(x: Number, y: Number, dx: Number, dy: Number) -> Number:
    """Squared distance from the origin to the segment from ``(x, y)`` to ``(x + dx, y + dy)``."""
    length2 = dx * dx + dy * dy
    if length2 > 0:
        k = -(x * dx + y * dy) / length2
        if k > 0:
            k = k if k < 1 else k * 0 + 1
            x, y = x + k * dx, y + k * dy
    return x * x + y * y


def moving_contact(
    d: tuple[Number, Number],
    v: tuple[Number, Number],
    a: tuple[Number, Number],
    span: Number,
    two_r: Number,
    margin: Number,
    tol: Number,
    max_iter: int,
) -> Number:
    """First contact time in ``[0, span]`` of two moving balls whose relative position is
    ``d + v t + a t^2`` (contact at distance ``two_r``), or :data:`NO_ROOT`."""
    dx, dy = d
    vx, vy = v
    ax, ay = a
    # Cheap rejection: the relative position stays within |a| span^2 / 4 of the chord from d to
    # its value at span; if that chord passes farther than 2R plus this bulge from the origin
    # (give or take the relative rounding ``margin``), no contact.
    ex = vx * span + ax * span * span
    ey = vy * span + ay * span * span
    bulge = sqrt(ax * ax + ay * ay) * span * span / 4
    limit = two_r * (1 + margin) + bulge
    if point_segment_gap2(dx, dy, ex, ey) > limit * limit:
        return NO_ROOT
    coeffs = (
        ax * ax + ay * ay,
        2 * (ax * vx + ay * vy),
        vx * vx + vy * vy + 2 * (ax * dx + ay * dy),
        2 * (vx * dx + vy * dy),
        dx * dx + dy * dy - two_r * two_r,
    )
    return first_contact(coeffs, span, tol, max_iter)
