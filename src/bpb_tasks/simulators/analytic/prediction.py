"""Event prediction for the analytic simulator: when will each ball next stop, hit a wall, enter a
pocket or touch another ball? (Conventions: :mod:`bpb_tasks.simulators.analytic`.)

Queue entries are ``(time, kind, index, other, version, other_version)`` tuples, so the heap
orders simultaneous events by kind and then by ball (lowest first); an entry is stale when a
ball's version has moved on since it was queued.
"""

from __future__ import annotations

import heapq
import math
from typing import Any

from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.simulators.analytic.motion import (
    Body,
    Motion,
    line_contact,
    moving_contact,
    pocket_entry,
    pocket_holding,
    time_for,
)
from bpb_tasks.simulators.analytic.numeric import Number, Numeric
from bpb_tasks.simulators.analytic.roots import NO_ROOT

BALL, WALL, POCKET, STOP = 0, 1, 2, 3
TOP, BOTTOM, LEFT, RIGHT = 0, 1, 2, 3


class Predictor:
    """Table geometry, the bodies and the event queue, with every prediction rule."""

    def __init__(self, scene: Scene, numeric: Numeric) -> None:
        num = numeric.num
        self.numeric = numeric
        phys = scene.physics
        radius = num(phys.ball_radius)
        self.motion = Motion(num(phys.mu) * num(phys.g))
        self.contact2 = 4 * radius * radius
        self.two_r = 2 * radius
        self.margin = num(1e-9)  # relative rounding margin of the cheap rejection test
        self.bounds = (
            radius,
            num(scene.table.width) - radius,
            radius,
            num(scene.table.height) - radius,
        )
        self.restitution = num(phys.wall_restitution)
        self.pocket_r = num(scene.pockets.radius)
        self.pockets = [(num(cx), num(cy)) for cx, cy in scene.pockets.centers]
        balls = sorted(scene.balls, key=lambda b: b.id)
        self.bodies = [Body(i, b.id, num(b.pos[0]), num(b.pos[1])) for i, b in enumerate(balls)]
        self.initial = [(num(b.vel[0]), num(b.vel[1])) for b in balls]
        self.queue: list[tuple[Any, ...]] = []
        self.horizon: Number = num(float("inf"))  # the run's end: no later event is queued

    def push(self, t: Number, kind: int, a: Body, k: int, other: Body | None = None) -> None:
        if t <= self.horizon:  # a later event cannot fire in this run
            ver = other.version if other is not None else 0
            heapq.heappush(self.queue, (t, kind, a.index, k, a.version, ver))

    def predict_single(self, b: Body) -> None:
        """Queue ``b``'s stop, next wall contacts and pocket entry (``b`` is at ``b.t0``)."""
        motion = self.motion
        b.wall_t = math.inf
        if b.speed == 0:
            return  # a resting ball enters no pocket (one it came to rest in has taken it)
        reach = math.inf  # the distance ``b`` still covers: for ever without friction
        if motion.decel > 0:
            self.push(b.tstop, STOP, b, 0)
            reach = b.speed * b.speed / (2 * motion.decel)
        xmin, xmax, ymin, ymax = self.bounds
        if b.uy != 0:
            wall, gap = (TOP, (ymax - b.y) / b.uy) if b.uy > 0 else (BOTTOM, (b.y - ymin) / -b.uy)
            self.predict_wall(b, wall, gap, reach)
        if b.ux != 0:
            wall, gap = (RIGHT, (xmax - b.x) / b.ux) if b.ux > 0 else (LEFT, (b.x - xmin) / -b.ux)
            self.predict_wall(b, wall, gap, reach)
        self.predict_pocket(b, reach)

    def pocket_at_start(self, b: Body) -> None:
        """Queue a pocket event at 0 for a resting ball placed within a pocket circle."""
        k = pocket_holding(b.x, b.y, self.pockets, self.pocket_r)
        if k >= 0:
            self.push(b.t0, POCKET, b, k)

    def predict_wall(self, b: Body, wall: int, gap: Number, reach: Number) -> None:
        gap = gap if gap > 0 else gap * 0
        if gap < reach:  # reaching the wall exactly as the ball stops is not a contact
            t = b.t0 + time_for(self.motion.decel, b.speed, gap)
            self.push(t, WALL, b, wall)
            b.wall_t = t if t < b.wall_t else b.wall_t

    def predict_pocket(self, b: Body, reach: Number) -> None:
        """Queue the first pocket ``b``'s centre enters (tangency counts) before it stops."""
        best, pocket = pocket_entry(b.x, b.y, b.ux, b.uy, self.pockets, self.pocket_r, reach)
        if best != NO_ROOT:
            t = b.t0 + (time_for(self.motion.decel, b.speed, best) if best > 0 else best)
            self.push(t, POCKET, b, pocket)

    def predict_pair(self, p: Body, q: Body, t: Number) -> None:
        """Queue the next contact of ``p`` and ``q`` after ``t``, if any."""
        if p.index > q.index:
            p, q = q, p
        if (p.speed == 0 or p.tstop <= t) and (q.speed == 0 or q.tstop <= t):
            return  # neither moves
        motion = self.motion
        px, py, ps = motion.state(p, t)
        qx, qy, qs = motion.state(q, t)
        if ps == 0 and qs == 0:
            return
        if ps == 0 or qs == 0:
            mx, my, ms, mover, rx, ry = (
                (px, py, ps, p, qx, qy) if qs == 0 else (qx, qy, qs, q, px, py)
            )
            s = line_contact(mx - rx, my - ry, mover.ux, mover.uy, self.contact2)
            if s == NO_ROOT:
                return
            reach = ms * ms / (2 * motion.decel) if motion.decel > 0 else math.inf
            if s < reach:  # stopping exactly at contact distance is not a collision
                self.push(t + (time_for(motion.decel, ms, s) if s > 0 else s), BALL, p, q.index, q)
            return
        tau = self.moving_pair(p, q, t, (px, py, qx, qy), (ps, qs))
        if tau != NO_ROOT:
            self.push(t + tau, BALL, p, q.index, q)

    def moving_pair(
        self, p: Body, q: Body, t: Number, ends: tuple[Number, ...], speeds: tuple[Number, Number]
    ) -> Number:
        """First contact time (from ``t``) of two moving balls at ``ends = (px, py, qx, qy)``,
        or :data:`NO_ROOT`."""
        span = min(p.tstop, q.tstop, p.wall_t, q.wall_t) - t
        if span < 0:
            return NO_ROOT
        ps, qs = speeds
        px, py, qx, qy = ends
        h = self.motion.half
        return moving_contact(
            (px - qx, py - qy),
            (p.ux * ps - q.ux * qs, p.uy * ps - q.uy * qs),
            ((q.ux - p.ux) * h, (q.uy - p.uy) * h),
            span,
            self.two_r,
            self.margin,
            self.numeric.time_tol,
            self.numeric.max_iter,
        )

    def predict_all(self, b: Body, t: Number, skip: Body | None = None) -> None:
        """Re-predict everything involving ``b``, which changed at ``t`` (pairs with ``skip`` are
        left to the caller)."""
        self.predict_single(b)
        self.predict_pairs(b, t, skip)

    def predict_pairs(self, b: Body, t: Number, skip: Body | None = None) -> None:
        """Queue ``b``'s contacts with every other ball; ``b`` is at its state at ``t``."""
        moving = b.speed > 0
        x, y, ux, uy, contact2 = b.x, b.y, b.ux, b.uy, self.contact2
        for other in self.bodies:
            if other is b or other is skip or not other.alive:
                continue
            if other.speed == 0:
                if not moving:
                    continue
                # Fast rejection against a resting ball: moving away, or the line misses it.
                dx, dy = x - other.x, y - other.y
                along = ux * dx + uy * dy
                if along >= 0:
                    continue
                c = dx * dx + dy * dy - contact2
                if c > 0 and along * along <= c:
                    continue
            self.predict_pair(b, other, t)
