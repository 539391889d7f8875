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
  (:mod:`bpb_tasks.simulators.analytic.roots`). After an event only the changed balls' events are
  re-predicted (queued events of a changed ball are invalidated by a version counter). Balls at rest
  cost nothing until something moves towards them.

* The outcome's event log holds ``ball`` (ids: the two balls, lower first), ``wall`` (ids: the
  ball; ``wall`` names it), ``pocket`` and ``stop`` (a moving ball comes to rest; no label uses
  it) events with the centres at that instant. Each ball's ``segments`` cover ``[0, horizon]``
  (or until pocketed): a new piece starts at every change of its motion (collision, wall,
  stop), so a piece is either pure deceleration or rest.

The same code runs on float64 or on 50-digit mpmath numbers (``precision=50``), the reference.
With numba installed (the ``fast`` extra) float64 runs can go through the compiled event kernel
(:mod:`bpb_tasks.simulators.analytic.kernel`), which performs the same operations in the same
order, so either gives the same numbers. :class:`AnalyticSimulator`'s ``engine`` chooses
between them (:meth:`AnalyticSimulator.takes_kernel`); this module's pure-Python loop is the
reference and the fallback.
"""

from __future__ import annotations

import copy
import heapq
import importlib.util
import os
import shutil
from collections.abc import Sequence

from bpb_core.errors import BadInput, BpbError
from bpb_tasks.billiards.scene.model import WALLS, Scene
from bpb_tasks.billiards.truth.outcome import Event, Outcome, Segment
from bpb_tasks.simulators.analytic.kernel_cache import (
    cache_folder,
    is_cached,
    note,
    numba_cache_dir,
    python_seconds,
    use_kernel,
)
from bpb_tasks.simulators.analytic.motion import Body
from bpb_tasks.simulators.analytic.numeric import FLOAT64, Number, Numeric, backend
from bpb_tasks.simulators.analytic.prediction import (
    BALL,
    BOTTOM,
    POCKET,
    RIGHT,
    STOP,
    TOP,
    WALL,
    Predictor,
)
from bpb_tasks.simulators.analytic.roots import sqrt

KIND_NAMES = ("ball", "wall", "pocket", "stop")
DEFAULT_MAX_EVENTS = 100_000


class SimulationError(BpbError):
    """A scene the simulator cannot finish: the analytic engine exceeded its event budget, or
    pymunk's step refused its scene, let a ball through a cushion or would exceed its budget
    of steps (those three about ``dt``: :meth:`~bpb_core.errors.BpbError.about`)."""


class AnalyticSimulator:
    """Exact event-driven simulator, registered as ``analytic``.

    Args:
        precision: ``None``/``"float64"`` (default) or a number of decimal digits for mpmath.
        max_events: Bound on processed events; exceeding it raises :class:`SimulationError`.
        engine: ``"auto"`` (the compiled kernel for float64 batches when numba has it cached or
            the work is worth building it; single runs once a batch loaded it), ``"kernel"``
            (require numba, for every run) or ``"python"`` (the pure-Python reference loop).
    """

    name = "analytic"

    def __init__(
        self,
        precision: str | int | None = None,
        max_events: int = DEFAULT_MAX_EVENTS,
        engine: str = "auto",
    ) -> None:
        if engine not in ("auto", "kernel", "python"):
            raise BadInput(f"engine: expected 'auto', 'kernel' or 'python', got {engine!r}")
        self.numeric = backend(precision)
        self.max_events = max_events
        self.engine = engine
        have_numba = importlib.util.find_spec("numba") is not None  # found, not imported
        self.available = have_numba and self.numeric is FLOAT64
        if engine == "kernel" and not self.available:
            raise BadInput("engine: 'kernel' needs numba (pip install 'bpb[fast]') and float64")
        self.kernel: bool | None = None  # loaded and running; False: it failed, said once
        self.cached: bool | None = None  # whether numba has it cached, once looked up
        self.spent = 0.0  # the Python engine's estimated CPU seconds in batches so far
        self.scenes = 1  # batches like the next one this command will run (expect_scenes)

    def with_max_events(self, max_events: int) -> AnalyticSimulator:
        """This simulator with another event budget (same precision and engine)."""
        other = copy.copy(self)
        other.max_events = max_events
        return other

    def kernel_loaded(self) -> bool:
        """Whether single runs take the kernel now: once a batch loaded it, or from the first
        run with ``engine="kernel"``."""
        return self.kernel is True

    def takes_kernel(self, scene: Scene, runs: int, events: float = 0.0) -> bool:
        """Whether a batch of ``runs`` simulations of scenes like ``scene`` (``events`` each,
        when known) takes the kernel
        (:func:`~bpb_tasks.simulators.analytic.kernel_cache.use_kernel`); the first time,
        it is loaded (built, with a note, when numba has not cached it): on a failure the
        Python engine runs from then on, said in a note."""
        if self.kernel is not None:
            return self.kernel
        if self.cached is None:
            self.cached = self.available and is_cached(numba_cache_dir(os.environ))
        seconds = python_seconds(runs, events)
        ahead = seconds * self.scenes  # this batch and the command's like it still to come
        if not use_kernel(self.engine, self.available, self.cached, self.spent, ahead):
            self.spent += seconds
            return False
        from bpb_tasks.simulators.analytic.compiled import kernel_failure
        from bpb_tasks.simulators.analytic.kernel import CACHE

        if CACHE and not self.cached:  # else kernel said it cannot cache it
            note(
                "compiling the physics kernel for this machine (about 20 s); cached in "
                f"{numba_cache_dir(os.environ)} for later commands"
            )
        failure = kernel_failure(scene)
        if failure is not None:
            note(f"the compiled physics kernel cannot be used ({failure}); using the Python engine")
            if numba_cache_dir(os.environ) == cache_folder():  # a folder the user named stays
                shutil.rmtree(cache_folder(), ignore_errors=True)  # the next command builds it
        self.kernel = failure is None
        return self.kernel

    def expect_scenes(self, count: int) -> None:
        """The command will make ``count`` scenes (:class:`~bpb_core.capabilities.ExpectsWork`):
        the engine choice weighs a scene's batch by them, so a command whose scenes together
        would cost the Python engine more than a compile builds the kernel at its first."""
        self.scenes = max(1, count)

    def run(self, scene: Scene, horizon: float | None = None) -> Outcome:
        """Simulate ``scene`` to ``horizon`` (default: the scene's own horizon)."""
        end = scene.horizon if horizon is None else horizon
        if self.kernel or (self.engine == "kernel" and self.takes_kernel(scene, 1)):
            from bpb_tasks.simulators.analytic.compiled import kernel_outcome

            return kernel_outcome(scene, end, self.max_events)
        return _Simulation(scene, self.numeric, self.max_events).run(end)

    def capped_events(self, scene: Scene, horizon: float) -> tuple[tuple[Event, ...], bool]:
        """The events of ``scene`` run to ``horizon`` by the pure-Python loop (any precision),
        and whether the run finished. A run exceeding ``max_events`` stops there instead of
        raising: the events are then those processed (the first ``max_events + 1``, in time
        order), and every later one is at or after the last one's time."""
        simulation = _Simulation(scene, self.numeric, self.max_events)
        try:
            simulation.run(horizon)
        except SimulationError:
            return tuple(simulation.events), False
        return tuple(simulation.events), True

    def run_many(self, scenes: Sequence[Scene], horizon: float | None = None) -> list[Outcome]:
        """Simulate scenes sharing one table to ``horizon`` (default: each scene's own): with
        the kernel in one compiled call
        (:func:`~bpb_tasks.simulators.analytic.compiled.outcomes_many`: outcomes without motion
        pieces, ``segments`` empty), else :meth:`run` on each."""
        if scenes and self.takes_kernel(scenes[0], len(scenes)):
            from bpb_tasks.simulators.analytic.compiled import outcomes_many

            ends = None if horizon is None else [horizon] * len(scenes)
            return outcomes_many(scenes, ends, self.max_events)
        return [self.run(s, horizon) for s in scenes]


class _Simulation(Predictor):
    """One run: prediction (:class:`Predictor`), event processing and the event log."""

    def __init__(self, scene: Scene, numeric: Numeric, max_events: int) -> None:
        super().__init__(scene, numeric)
        self.max_events = max_events
        self.events: list[Event] = []
        self.ended: dict[int, Number] = {}

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
        norm = sqrt(nx * nx + ny * ny)
        nx, ny = nx / norm, ny / norm
        pvx, pvy, qvx, qvy = p.ux * ps, p.uy * ps, q.ux * qs, q.uy * qs
        vn = (pvx - qvx) * nx + (pvy - qvy) * ny
        if not vn > self.numeric.speed_tol * (ps + qs):
            # Not approaching, or by less than the rounding of the speeds themselves: then the
            # exchange cannot change the faster ball, the pair still approaches and the same
            # contact would be found again at the same time, forever (a rack break left a ball
            # at 3e-15 m/s touching one whose 2e-31 m/s share stopped it within the same
            # instant). Nothing measurable would change: it is not a collision.
            return False
        p.x, p.y, q.x, q.y = px, py, qx, qy
        self.changed(p, t, pvx - vn * nx, pvy - vn * ny)
        self.changed(q, t, qvx + vn * nx, qvy + vn * ny)
        self.log(t, BALL, (p, q))
        self.predict_all(p, t)
        self.predict_all(q, t, skip=p)
        return True

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
        self.horizon = horizon
        for b, (vx, vy) in zip(self.bodies, self.initial, strict=True):
            self.motion.set_velocity(b, zero, vx, vy)
            b.seg.append((zero, b.x, b.y, vx, vy))
        for b in self.bodies:
            if b.speed > 0:
                self.predict_single(b)
            else:
                self.pocket_at_start(b)
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
            elif kind == WALL:  # wall ``k``: its normal velocity reversed and scaled
                self.motion.advance(b, t)
                xmin, xmax, ymin, ymax = self.bounds
                vx, vy = b.ux * b.speed, b.uy * b.speed
                if k in (TOP, BOTTOM):
                    b.y = ymax if k == TOP else ymin
                    vy = -vy * self.restitution
                else:
                    b.x = xmax if k == RIGHT else xmin
                    vx = -vx * self.restitution
                self.changed(b, t, vx, vy)
                self.log(t, WALL, (b,), WALLS[k])
                self.predict_all(b, t)
            elif kind == POCKET:
                self.motion.advance(b, t)
                b.alive = False
                b.version += 1
                self.ended[b.index] = t
                self.log(t, POCKET, (b,))
            else:  # the ball stops
                self.motion.advance(b, t)
                self.changed(b, t, b.speed * 0, b.speed * 0)
                self.log(t, STOP, (b,))
                self.predict_pairs(b, t)
            count += 1
            if count > self.max_events:
                raise SimulationError(
                    f"more than {self.max_events} events before t={float(horizon)}"
                )

    def outcome(self, horizon_in: float, horizon: Number) -> Outcome:
        """The final positions, the event log and each ball's pieces of motion as public
        floats (a ball's last piece ends at the horizon, or where it was pocketed)."""
        positions: dict[int, tuple[float, float] | None] = {}
        segments: dict[int, tuple[Segment, ...]] = {}
        exact = self.numeric.num is not float
        decel = float(self.motion.decel)
        for b in self.bodies:
            if b.alive:
                x, y, _ = self.motion.state(b, horizon)
                positions[b.id] = (float(x), float(y)) if exact else (x, y)
            else:
                positions[b.id] = None
            end: Number = self.ended.get(b.index, horizon)
            seg, pieces = b.seg, []
            for i, (t0, x, y, vx, vy) in enumerate(seg):
                t1 = seg[i + 1][0] if i + 1 < len(seg) else end
                if exact:
                    t0, t1, x, y, vx, vy = (float(v) for v in (t0, t1, x, y, vx, vy))
                pieces.append(Segment(t0, t1, (x, y), (vx, vy), decel))
            segments[b.id] = tuple(pieces)
        return Outcome(horizon_in, positions, tuple(self.events), segments)
