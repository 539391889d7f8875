"""The ``analytic`` simulator: exact event-driven billiards (SPEC sections 2-3).

Physics conventions (the data contract; the dataset card quotes them):

* Balls slide with constant deceleration ``a = mu g`` along their velocity: the speed falls as
  ``v0 - a t`` and the distance covered is ``s(t) = v0 t - a t^2 / 2`` until the ball stops at
  ``v0 / a``; it then rests until hit. No spin, no rolling.
* Ball-ball contact: the centre distance reaches ``2R`` while the pair approaches (normal relative
  velocity towards each other). The collision is elastic, frictionless, equal masses: the normal
  components of the velocities are exchanged. A pair that starts touching or overlapping (up to
  1e-9 m) collides at once if it approaches and is ignored if it recedes (Bannerman et al. 2014);
  detection and resolution use the same approach test, so a processed collision never recurs.
  A contact with zero normal relative speed (grazing tangency, a ball stopping exactly at contact
  distance) is not a collision.
* Wall contact: the centre is ``R`` from the wall while the ball moves towards it. The normal
  velocity component is reversed and scaled by ``wall_restitution`` (default 1). A ball lying
  against a wall or leaving it has not hit it; one touching it and moving into it hits at once.
* Pockets: a ball is pocketed at the first instant its centre is within the pocket radius
  (tangency counts) and is removed from the table; its position is then ``None``.
* Events in the closed interval ``[0, horizon]`` count. Simultaneous events are processed in the
  order (time, kind, ids): kinds ``ball < wall < pocket < stop``; ball events by the lower then
  the higher id; a ball's wall events by the order TOP, BOTTOM, LEFT, RIGHT (so an exact corner
  hit records both walls, the TOP/BOTTOM one first); pockets by their index in the scene.
* A moving ball against a resting one, a wall or a pocket has a closed-form contact time; only two
  moving balls need a quartic, solved by root isolation and bracketed refinement
  (:mod:`bpb_tasks.simulators.analytic_roots`). After an event only the changed balls' events are
  re-predicted (queued events of a changed ball are invalidated by a version counter). Balls at rest
  cost nothing until something moves towards them.

The same code runs on float64 or on 50-digit mpmath numbers (``precision=50``), the reference.
"""

from __future__ import annotations

import heapq
from typing import Any

from bpb_core.errors import BpbError
from bpb_core.outcome import Event, Outcome, Segment
from bpb_core.scene import WALLS, Scene
from bpb_tasks.simulators.analytic_motion import Body, Motion, circle_entry, line_contact
from bpb_tasks.simulators.analytic_roots import first_contact
from bpb_tasks.simulators.numeric import Number, Numeric, backend

BALL, WALL, POCKET, STOP = 0, 1, 2, 3
KIND_NAMES = ("ball", "wall", "pocket", "stop")
TOP, BOTTOM, LEFT, RIGHT = 0, 1, 2, 3
DEFAULT_MAX_EVENTS = 100_000


class SimulationError(BpbError):
    """The simulation exceeded its event budget (a scene the simulator cannot finish)."""


class AnalyticSimulator:
    """Exact event-driven simulator, registered as ``analytic``.

    Args:
        precision: ``None``/``"float64"`` (default) or a number of decimal digits for mpmath.
        max_events: Bound on processed events; exceeding it raises :class:`SimulationError`.
    """

    name = "analytic"

    def __init__(
        self, precision: str | int | None = None, max_events: int = DEFAULT_MAX_EVENTS
    ) -> None:
        self.numeric = backend(precision)
        self.max_events = max_events

    def run(self, scene: Scene, horizon: float | None = None) -> Outcome:
        """Simulate ``scene`` to ``horizon`` (default: the scene's own horizon)."""
        end = scene.horizon if horizon is None else horizon
        return _Simulation(scene, self.numeric, self.max_events).run(end)


class _Simulation:
    """One run: bodies, the event queue and the event log."""

    def __init__(self, scene: Scene, numeric: Numeric, max_events: int) -> None:
        num = numeric.num
        self.numeric = numeric
        self.sqrt = numeric.sqrt
        self.max_events = max_events
        phys = scene.physics
        radius = num(phys.ball_radius)
        self.motion = Motion(num(phys.mu) * num(phys.g), numeric.sqrt, num(float("inf")))
        self.contact2 = 4 * radius * radius
        self.two_r = 2 * radius
        self.bounds = (
            radius,
            num(scene.table.width) - radius,
            radius,
            num(scene.table.height) - radius,
        )
        self.restitution = num(phys.wall_restitution)
        self.pocket_r = num(scene.pockets.radius)
        self.pocket_r2 = self.pocket_r * self.pocket_r
        self.pockets = [(num(cx), num(cy)) for cx, cy in scene.pockets.centers]
        balls = sorted(scene.balls, key=lambda b: b.id)
        self.bodies = [Body(i, b.id, num(b.pos[0]), num(b.pos[1])) for i, b in enumerate(balls)]
        self.initial = [(num(b.vel[0]), num(b.vel[1])) for b in balls]
        self.queue: list[tuple[Any, ...]] = []
        self.events: list[Event] = []
        self.ended: dict[int, Number] = {}

    # --- prediction -------------------------------------------------------------------------
    def push(self, t: Number, kind: int, a: Body, k: int, other: Body | None = None) -> None:
        ver = other.version if other is not None else 0
        heapq.heappush(self.queue, (t, kind, a.index, k, a.version, ver))

    def predict_single(self, b: Body) -> None:
        """Queue ``b``'s stop, next wall contacts and pocket entry (``b`` is at ``b.t0``)."""
        motion = self.motion
        b.wall_t = motion.inf
        if b.speed == 0:
            self.predict_pocket(b, b.speed)
            return
        if motion.decel > 0:
            self.push(b.tstop, STOP, b, 0)
        reach = motion.reach(b)
        xmin, xmax, ymin, ymax = self.bounds
        if b.uy != 0:
            wall, gap = (TOP, (ymax - b.y) / b.uy) if b.uy > 0 else (BOTTOM, (b.y - ymin) / -b.uy)
            self.predict_wall(b, wall, gap, reach)
        if b.ux != 0:
            wall, gap = (RIGHT, (xmax - b.x) / b.ux) if b.ux > 0 else (LEFT, (b.x - xmin) / -b.ux)
            self.predict_wall(b, wall, gap, reach)
        self.predict_pocket(b, reach)

    def predict_wall(self, b: Body, wall: int, gap: Number, reach: Number) -> None:
        gap = gap if gap > 0 else gap * 0
        if gap < reach:  # reaching the wall exactly as the ball stops is not a contact
            t = b.t0 + self.motion.time_for(b.speed, gap)
            self.push(t, WALL, b, wall)
            b.wall_t = t if t < b.wall_t else b.wall_t

    def predict_pocket(self, b: Body, reach: Number) -> None:
        best: tuple[Number, int] | None = None
        x, y, r2 = b.x, b.y, self.pocket_r2
        far = (reach + self.pocket_r) ** 2 if reach < self.motion.inf else reach
        for k, (cx, cy) in enumerate(self.pockets):
            dx, dy = x - cx, y - cy
            if dx * dx + dy * dy > far:
                continue  # out of reach: cannot enter this pocket before stopping
            s = circle_entry(dx, dy, b.ux, b.uy, r2, self.sqrt)
            if s is not None and s <= reach and (best is None or s < best[0]):
                best = (s, k)
        if best is not None:
            t = b.t0 + (self.motion.time_for(b.speed, best[0]) if best[0] > 0 else best[0])
            self.push(t, POCKET, b, best[1])

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
            s = line_contact(mx - rx, my - ry, mover.ux, mover.uy, self.contact2, self.sqrt)
            if s is None:
                return
            reach = ms * ms / (2 * motion.decel) if motion.decel > 0 else motion.inf
            if s < reach:  # stopping exactly at contact distance is not a collision
                tau = motion.time_for(ms, s) if s > 0 else s
                heapq.heappush(self.queue, (t + tau, BALL, p.index, q.index, p.version, q.version))
            return
        tau = self.moving_pair(p, q, t, (px - qx, py - qy), (ps, qs))
        if tau is not None:
            heapq.heappush(self.queue, (t + tau, BALL, p.index, q.index, p.version, q.version))

    def moving_pair(
        self, p: Body, q: Body, t: Number, d0: tuple[Number, Number], speeds: tuple[Number, Number]
    ) -> Number | None:
        """First contact time (from ``t``) of two moving balls, by the quartic."""
        horizon = min(p.tstop, q.tstop, p.wall_t, q.wall_t) - t
        if horizon < 0:
            return None
        ps, qs = speeds
        vx, vy = p.ux * ps - q.ux * qs, p.uy * ps - q.uy * qs
        h = self.motion.half
        ax, ay = (q.ux - p.ux) * h, (q.uy - p.uy) * h
        dx, dy = d0
        if not self.paths_can_meet(d0, (vx, vy), (ax, ay), horizon):
            return None
        coeffs = [
            ax * ax + ay * ay,
            2 * (ax * vx + ay * vy),
            vx * vx + vy * vy + 2 * (ax * dx + ay * dy),
            2 * (vx * dx + vy * dy),
            dx * dx + dy * dy - self.contact2,
        ]
        return first_contact(coeffs, horizon, self.numeric)

    def paths_can_meet(
        self,
        d0: tuple[Number, Number],
        v: tuple[Number, Number],
        a: tuple[Number, Number],
        span: Number,
    ) -> bool:
        """Cheap rejection: bound the relative displacement ``|v| T + |a| T^2`` over the span."""
        dist = self.sqrt(d0[0] * d0[0] + d0[1] * d0[1])
        reach = self.sqrt(v[0] * v[0] + v[1] * v[1]) * span
        reach += self.sqrt(a[0] * a[0] + a[1] * a[1]) * span * span
        return bool(dist - reach <= self.two_r)

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

    # --- processing ----------------------------------------------------------------------------
    def changed(self, b: Body, t: Number, vx: Number, vy: Number) -> None:
        """Give ``b`` a new velocity at ``t`` (it must already be at its position at ``t``)."""
        self.motion.set_velocity(b, t, vx, vy)
        b.version += 1
        b.seg.append((t, b.x, b.y, vx, vy))

    def collide(self, p: Body, q: Body, t: Number) -> bool:
        motion = self.motion
        px, py, ps = motion.state(p, t)
        qx, qy, qs = motion.state(q, t)
        nx, ny = qx - px, qy - py
        norm = self.sqrt(nx * nx + ny * ny)
        nx, ny = nx / norm, ny / norm
        pvx, pvy, qvx, qvy = p.ux * ps, p.uy * ps, q.ux * qs, q.uy * qs
        vn = (pvx - qvx) * nx + (pvy - qvy) * ny
        if not vn > 0:
            return False  # not approaching: no collision (same test as detection)
        p.x, p.y, q.x, q.y = px, py, qx, qy
        self.changed(p, t, pvx - vn * nx, pvy - vn * ny)
        self.changed(q, t, qvx + vn * nx, qvy + vn * ny)
        self.log(t, BALL, (p, q))
        self.predict_all(p, t)
        self.predict_all(q, t, skip=p)
        return True

    def bounce(self, b: Body, t: Number, wall: int) -> None:
        self.motion.advance(b, t)
        xmin, xmax, ymin, ymax = self.bounds
        vx, vy = b.ux * b.speed, b.uy * b.speed
        if wall in (TOP, BOTTOM):
            b.y = ymax if wall == TOP else ymin
            vy = -vy * self.restitution
        else:
            b.x = xmax if wall == RIGHT else xmin
            vx = -vx * self.restitution
        self.changed(b, t, vx, vy)
        self.log(t, WALL, (b,), WALLS[wall])
        self.predict_all(b, t)

    def pocket(self, b: Body, t: Number) -> None:
        self.motion.advance(b, t)
        b.alive = False
        b.version += 1
        self.ended[b.index] = t
        self.log(t, POCKET, (b,))

    def stop(self, b: Body, t: Number) -> None:
        self.motion.advance(b, t)
        self.changed(b, t, b.speed * 0, b.speed * 0)
        self.log(t, STOP, (b,))
        self.predict_pairs(b, t)

    def log(self, t: Number, kind: int, bodies: tuple[Body, ...], wall: str | None = None) -> None:
        self.events.append(
            Event(
                float(t),
                KIND_NAMES[kind],
                tuple(b.id for b in bodies),
                wall,
                tuple((float(b.x), float(b.y)) for b in bodies),
            )
        )

    def run(self, horizon_in: float) -> Outcome:
        zero, horizon = self.numeric.num(0.0), self.numeric.num(horizon_in)
        for b, (vx, vy) in zip(self.bodies, self.initial, strict=True):
            self.motion.set_velocity(b, zero, vx, vy)
            b.seg.append((zero, b.x, b.y, vx, vy))
        for b in self.bodies:
            self.predict_single(b)
        for b in self.bodies:
            if b.speed > 0:
                self.predict_pairs(b, zero, None)
        self.loop(horizon)
        return self.outcome(horizon_in, horizon)

    def loop(self, horizon: Number) -> None:
        bodies, queue, count = self.bodies, self.queue, 0
        while queue and queue[0][0] <= horizon:
            t, kind, i, k, ver_i, ver_k = heapq.heappop(queue)
            b = bodies[i]
            if b.version != ver_i or not b.alive:
                continue
            if kind == BALL:
                other = bodies[k]
                if other.version != ver_k or not other.alive or not self.collide(b, other, t):
                    continue
            elif kind == WALL:
                self.bounce(b, t, k)
            elif kind == POCKET:
                self.pocket(b, t)
            else:
                self.stop(b, t)
            count += 1
            if count > self.max_events:
                raise SimulationError(
                    f"more than {self.max_events} events before t={float(horizon)}"
                )

    def outcome(self, horizon_in: float, horizon: Number) -> Outcome:
        positions: dict[int, tuple[float, float] | None] = {}
        segments: dict[int, tuple[Segment, ...]] = {}
        exact = self.numeric.num is not float
        for b in self.bodies:
            if b.alive:
                x, y, _ = self.motion.state(b, horizon)
                positions[b.id] = (float(x), float(y)) if exact else (x, y)
            else:
                positions[b.id] = None
            segments[b.id] = self.segments_of(b, self.ended.get(b.index, horizon), exact)
        return Outcome(horizon_in, positions, tuple(self.events), segments)

    def segments_of(self, b: Body, end: Number, exact: bool) -> tuple[Segment, ...]:
        """``b``'s pieces of motion as public floats (the last one ends at ``end``)."""
        decel = float(self.motion.decel)
        ends = [s[0] for s in b.seg[1:]]
        ends.append(end)
        if exact:
            return tuple(
                Segment(float(t0), float(t1), (float(x), float(y)), (float(vx), float(vy)), decel)
                for (t0, x, y, vx, vy), t1 in zip(b.seg, ends, strict=True)
            )
        return tuple(
            Segment(t0, t1, (x, y), (vx, vy), decel)
            for (t0, x, y, vx, vy), t1 in zip(b.seg, ends, strict=True)
        )
