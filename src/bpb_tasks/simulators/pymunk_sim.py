"""The ``pymunk`` simulator: fixed-step Chipmunk2D, to show what a general engine costs and errs.

Same scene format and conventions as ``analytic`` where a fixed-step engine can follow them:

* Balls are pymunk circles of mass 1 with infinite moment (no spin), elasticity 1 and no surface
  friction; walls are static segments on the table edges with elasticity ``wall_restitution``.
  Gravity is off; the collision slop is scaled to metres (``1e-4 R``) instead of pixels.
* Sliding friction is applied exactly between steps: each moving ball's speed drops by
  ``mu g dt`` along its velocity, to zero without reversal (a ``stop`` event).
* Pockets are checked after every step: a ball whose centre is within the pocket radius is
  removed and a ``pocket`` event recorded.
* Contacts come from pymunk's ``begin`` collision callback; like ``analytic``, a ball-ball contact
  counts only while the pair approaches and a wall contact only while the ball moves towards the
  wall. Event times are the end of the step in which pymunk saw them, so they carry an error of
  up to ``dt``; the last step is shortened to land exactly on the horizon.
* A step may carry no ball further than half its radius: a ``dt`` above the scene's
  :func:`stable_dt` is refused (:meth:`PymunkSimulator.run`). No ``dt`` is chosen from the bound
  instead: the step is part of the truth, one number the user chose and the manifest records.
  Beyond the bound pymunk tunnels: at three times it 26 of 60 random scenes (cue at 0.5-6 m/s)
  ended a ball off the table, and at twice it a ball squeezed between a cushion and a fast
  stack of balls now and then went through.
* Final positions lie on the table as a scene file's balls do, ``R`` from every cushion
  (:func:`bpb_tasks.billiards.scene.model.table_box`): a ball the horizon catches sunk into a
  cushion is put back against it; a ball whose centre crossed a cushion fails the run rather
  than give that position as the truth.
* ``tunnel="allow"`` (``pymunk:dt=0.01,tunnel=allow`` as a ``bpb bench sim`` contestant) turns
  the last two points off: any ``dt`` is taken and the final positions are pymunk's own. That is
  what ``bpb bench sim`` measures; ground truth keeps the default ``tunnel="refuse"``.
"""

from __future__ import annotations

import math
import sys
from typing import Any

from bpb_core.errors import BadInput, need_module
from bpb_tasks.billiards.scene.model import Scene, table_box
from bpb_tasks.billiards.truth.outcome import Event, Outcome, Segment
from bpb_tasks.simulators.analytic.engine import SimulationError

MAX_STEPS = 10_000_000  # about an hour of stepping: refuse rather than run for days
TUNNEL = ("refuse", "allow")
"""Values of :class:`PymunkSimulator`'s ``tunnel`` option, the default first."""
_WALL_NORMALS = {"TOP": (0.0, 1.0), "BOTTOM": (0.0, -1.0), "LEFT": (-1.0, 0.0), "RIGHT": (1.0, 0.0)}


class PymunkSimulator:
    """Fixed-step simulator, registered as ``pymunk``.

    Args:
        dt: Time step in seconds (default 1e-3).
        tunnel: ``"refuse"`` (default) a ``dt`` above the scene's :func:`stable_dt` and a ball
            off the table, or ``"allow"`` them: pymunk exactly as it steps (see the module).
    """

    name = "pymunk"

    def __init__(self, dt: float = 1e-3, tunnel: str = "refuse") -> None:
        if isinstance(dt, bool) or not isinstance(dt, int | float) or not 0 < dt < math.inf:
            raise BadInput.about("dt", f"must be a positive finite number of seconds, got {dt!r}")
        if tunnel not in TUNNEL:
            raise BadInput.about("tunnel", f"must be {' or '.join(TUNNEL)}, got {tunnel!r}")
        self.dt, self.tunnel = dt, tunnel

    def run(self, scene: Scene, horizon: float | None = None) -> Outcome:
        """Simulate ``scene`` to ``horizon`` (default: the scene's own horizon).

        Raises:
            SimulationError: ``dt`` is above the scene's :func:`stable_dt`, a ball left the
                table all the same, or the run would take more than :data:`MAX_STEPS` steps;
                each message starts ``dt:`` (its ``option``), for the caller to name where
                ``dt`` is set (``bpb simulate`` the scene file and ``--dt``, ``bpb generate``
                the config's ``simulator``).
        """
        end = scene.horizon if horizon is None else horizon
        return self._started(scene).run(end)

    def events_until_failure(
        self, scene: Scene, end: float
    ) -> tuple[tuple[Event, ...], float | None]:
        """The events of ``scene`` run to ``end`` as :meth:`run` runs it, stopped where that run
        would fail instead of failing: at the step where a ball went through a cushion, or
        where the :data:`MAX_STEPS` budget runs out. Returns the events and ``None`` when the
        run reached ``end`` (or nothing moves any more), else the time it stopped at: every
        later event is at or after it. The stability annotation's run past the horizon, like
        :meth:`~bpb_tasks.simulators.analytic.AnalyticSimulator.capped_events`.

        Raises:
            SimulationError: ``dt`` is above the scene's :func:`stable_dt`, as in :meth:`run`.
        """
        return self._started(scene).events_until_failure(end)

    def _started(self, scene: Scene) -> _PymunkRun:
        """A run of ``scene``, once ``dt`` is within its bound (see :meth:`run`)."""
        bound = stable_dt(scene)
        if self.tunnel == "refuse" and self.dt > bound:
            radius = scene.physics.ball_radius
            scale = 10.0 ** (2 - math.floor(math.log10(bound)))  # 3 digits, rounded down: within
            raise SimulationError.about(
                "dt",
                f"{self.dt:g} s is above this scene's stability bound, "
                f"{math.floor(bound * scale) / scale:.3g} s "
                f"(half the ball radius, {radius / 2:g} m, over the fastest possible speed, "
                f"{radius / (2 * bound):.4g} m/s): a longer step can carry a ball through a "
                "cushion",
            )
        return _PymunkRun(scene, self.dt, on_table=self.tunnel == "refuse")


def stable_dt(scene: Scene) -> float:
    """The largest ``dt`` pymunk takes for ``scene`` (``inf`` when nothing moves): half the
    ball radius over ``sqrt(sum v^2)`` of the balls' speeds, which bounds every ball's speed
    all along (elastic contacts keep it, friction and cushions only lower it). A step of the
    whole radius lets a ball pushed by others cross a cushion before pymunk pushes it back."""
    speed = math.sqrt(sum(vx * vx + vy * vy for vx, vy in (b.vel for b in scene.balls)))
    return scene.physics.ball_radius / (2 * speed) if speed > 0 else math.inf


class _PymunkRun:
    def __init__(self, scene: Scene, dt: float, on_table: bool = True) -> None:
        """``on_table``: fail a ball off the table and put back one sunk into a cushion."""
        pymunk = need_module("pymunk", "the pymunk simulator", "pip install 'bpb[pymunk]'")

        self.scene, self.dt, self.t, self.on_table = scene, dt, 0.0, on_table
        phys = scene.physics
        self.decel = phys.mu * phys.g
        self.space = pymunk.Space()
        self.space.collision_slop = 1e-4 * phys.ball_radius
        self.bodies: dict[int, Any] = {}
        self.owner: dict[Any, tuple[str, Any]] = {}
        self.events: list[Event] = []
        self.touched: set[int] = set()
        self.active: set[int] = set()  # balls that may be moving
        self.segments: dict[int, list[tuple[float, tuple[float, float], tuple[float, float]]]] = {}
        self.ended: dict[int, float] = {}
        for ball in sorted(scene.balls, key=lambda b: b.id):
            body = pymunk.Body(1.0, math.inf)
            body.position = ball.pos
            body.velocity = ball.vel
            shape = pymunk.Circle(body, phys.ball_radius)
            shape.elasticity, shape.friction = 1.0, 0.0
            self.space.add(body, shape)
            self.bodies[ball.id] = body
            self.owner[shape] = ("ball", ball.id)
            self.segments[ball.id] = [(0.0, ball.pos, ball.vel)]
            self.active.add(ball.id)  # resting ones leave after the first step
        w, h = scene.table.width, scene.table.height
        corners = {
            "TOP": ((0.0, h), (w, h)),
            "BOTTOM": ((0.0, 0.0), (w, 0.0)),
            "LEFT": ((0.0, 0.0), (0.0, h)),
            "RIGHT": ((w, 0.0), (w, h)),
        }
        for name, (a, b) in corners.items():
            wall = pymunk.Segment(self.space.static_body, a, b, 0.0)
            wall.elasticity = phys.wall_restitution
            wall.friction = 0.0
            self.space.add(wall)
            self.owner[wall] = ("wall", name)
        self.space.on_collision(begin=self._begin)
        self.box = table_box(scene.table, phys.ball_radius)

    def _begin(self, arbiter: Any, space: Any, data: Any) -> None:
        """Log a wall contact while the ball moves towards the wall, a ball contact while the
        pair approaches."""
        first, second = (self.owner[s] for s in arbiter.shapes)
        self.active.update(o[1] for o in (first, second) if o[0] == "ball")
        if first[0] == "wall":
            first, second = second, first
        if second[0] == "wall":
            velocity = self.bodies[first[1]].velocity
            nx, ny = _WALL_NORMALS[second[1]]
            if velocity.x * nx + velocity.y * ny > 0:
                self._log("wall", (first[1],), second[1])
            return
        a, b = min(first[1], second[1]), max(first[1], second[1])
        pa, pb = self.bodies[a], self.bodies[b]
        if (pa.velocity - pb.velocity).dot(pb.position - pa.position) > 0:
            self._log("ball", (a, b), None)

    def _log(self, kind: str, ids: tuple[int, ...], wall: str | None) -> None:
        positions = tuple((self.bodies[i].position.x, self.bodies[i].position.y) for i in ids)
        self.events.append(Event(self.t, kind, ids, wall, positions))
        self.touched.update(ids)

    def _check_budget(self, horizon: float) -> None:
        """Refuse a run whose balls may still move after :data:`MAX_STEPS` steps.

        Friction takes ``mu g`` per second off the root of the summed squared speeds (elastic
        contacts keep it, so it bounds every ball's speed), so all balls rest by
        ``sqrt(sum v^2) / (mu g)``; stepping stops then. Without friction they never rest.
        """
        if not math.isfinite(horizon / self.dt):  # the step count overflows a float
            raise SimulationError.about(
                "dt",
                f"t={horizon:g} is more steps of {self.dt:g} s than can be counted; use a "
                f"horizon under {sys.float_info.max * self.dt:.3g} s or a larger dt",
            )
        steps = min(horizon, self._moving_for()) / self.dt
        if steps > MAX_STEPS:
            raise SimulationError.about(
                "dt",
                f"{steps:.3g} steps of {self.dt:g} s to reach t={horizon:g} with balls still "
                f"moving (at most {MAX_STEPS:,}); use a shorter horizon or a larger dt",
            )

    def _moving_for(self) -> float:
        """A time by which every ball rests, plus a second (see :meth:`_check_budget`)."""
        speed = math.sqrt(sum(vx * vx + vy * vy for vx, vy in (b.vel for b in self.scene.balls)))
        resting_by = speed / self.decel if self.decel > 0 else (0.0 if speed == 0 else math.inf)
        return resting_by + 1.0

    def run(self, horizon: float) -> Outcome:
        self._check_budget(horizon)
        self._step_to(horizon)
        positions: dict[int, tuple[float, float] | None] = {}
        segments: dict[int, tuple[Segment, ...]] = {}
        for ball, body in self.bodies.items():
            gone = ball in self.ended
            positions[ball] = None if gone else self._on_table(ball, body.position)
            starts = self.segments[ball]
            ends = [s[0] for s in starts[1:]] + [self.ended.get(ball, horizon)]
            segments[ball] = tuple(
                Segment(t0, t1, pos, vel, self.decel)
                for (t0, pos, vel), t1 in zip(starts, ends, strict=True)
            )
        return Outcome(horizon, positions, tuple(self.events), segments)

    def events_until_failure(self, end: float) -> tuple[tuple[Event, ...], float | None]:
        """See :meth:`PymunkSimulator.events_until_failure`. A ball through a cushion stops
        the run at the end of the step that moved it (events of that step not yet logged, a
        pocket, are at that time), the step budget at the last step it allows
        (:data:`MAX_STEPS` of them, when balls may still move then)."""
        reach = end if self._moving_for() / self.dt <= MAX_STEPS else min(end, MAX_STEPS * self.dt)
        try:
            self._step_to(reach)
        except SimulationError:
            return tuple(self.events), self.t
        return tuple(self.events), None if reach == end or not self.active else reach

    def _step_to(self, horizon: float) -> None:
        """Step from ``t = 0`` to ``horizon``, the last step shortened to land on it."""
        steps = max(math.floor(horizon / self.dt + 1e-9), 0)
        last = horizon - steps * self.dt
        for index in range(steps + 1):
            size = self.dt if index < steps else last
            if size <= 1e-12:
                break
            if not self.active:  # nothing moves any more: the rest changes nothing
                self.t = horizon
                break
            self.t += size
            self.space.step(size)
            drop = self.decel * size  # friction, exactly between steps
            for ball in list(self.active):
                body = self.bodies[ball]
                vx, vy = body.velocity
                speed = math.hypot(vx, vy)
                if speed <= drop:
                    body.velocity = (0.0, 0.0)
                    self.active.discard(ball)
                    if speed > 0:
                        self._log("stop", (ball,), None)
                else:
                    scale = (speed - drop) / speed
                    body.velocity = (vx * scale, vy * scale)
            self._pockets()
            for ball in self.touched - self.ended.keys():
                body = self.bodies[ball]
                pos, vel = body.position, body.velocity
                self.segments[ball].append((self.t, (pos.x, pos.y), (vel.x, vel.y)))
            self.touched.clear()

    def _pockets(self) -> None:
        pockets, width, height = self.scene.pockets, self.scene.table.width, self.scene.table.height
        for ball in list(self.active):
            body = self.bodies[ball]
            x, y = body.position
            # hypot, not squares: a far pocket centre (1e300 m) would overflow ** 2
            if any(math.hypot(x - cx, y - cy) <= pockets.radius for cx, cy in pockets.centers):
                self._log("pocket", (ball,), None)
                self.ended[ball] = self.t
                self.active.discard(ball)
                self.space.remove(body, *body.shapes)
            elif self.on_table and not (0.0 <= x <= width and 0.0 <= y <= height):
                self._through(ball, x, y)

    def _through(self, ball: int, x: float, y: float) -> None:
        """Fail the run: ``ball``'s centre at ``(x, y)`` has crossed a cushion."""
        raise SimulationError.about(
            "dt",
            f"{self.dt:g} s let ball {ball} go through a cushion by t={self.t:.6g} (centre at "
            f"({x:.4g}, {y:.4g}), off the table); use a smaller dt",
        )

    def _on_table(self, ball: int, position: Any) -> tuple[float, float]:
        """``position`` put back against any cushion it has sunk into (see the module);
        as it is when tunnelling is allowed."""
        x, y = position
        if not self.on_table:
            return (x, y)
        if not (0.0 <= x <= self.scene.table.width and 0.0 <= y <= self.scene.table.height):
            self._through(ball, x, y)
        lo_x, hi_x, lo_y, hi_y = self.box
        return (min(max(x, lo_x), hi_x), min(max(y, lo_y), hi_y))
