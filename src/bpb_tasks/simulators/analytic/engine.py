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

The same code runs on float64 or on 50-digit mpmath numbers (``precision=50``), the reference
(:class:`Numeric`): it only uses ``+ - * /``, comparisons, ``roots.sqrt`` and
:attr:`Numeric.num` (to lift an input float), which Python floats and ``mpmath`` numbers both
support, so choosing a backend at construction is all it takes to run the identical algorithm
in 50-digit arithmetic.
With numba installed (the ``fast`` extra) float64 runs can go through the compiled event kernel
(:mod:`bpb_tasks.simulators.analytic.kernel`), which performs the same operations in the same
order, so either gives the same numbers. :class:`AnalyticSimulator`'s ``engine`` chooses
between them (:meth:`AnalyticSimulator.takes_kernel`, by :func:`use_kernel`: the compiled
kernel when it is cached, or when the work of a command is worth building it; the Python engine
otherwise); this module's pure-Python loop is the reference and the fallback.

numba caches the compiled kernel in a folder keyed by bpb's version and a hash of every
compiled module's source (:func:`cache_folder`), so an edit or upgrade of any of them, callee or
caller, starts a new folder: numba itself checks a cached function against its own file only.
Unless the user set ``NUMBA_CACHE_DIR``, :mod:`~bpb_tasks.simulators.analytic.kernel` sets it to
that folder before it imports numba; this module imports the kernel, and so numba, only when
a batch takes it.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
import heapq
import importlib.util
import math
import os
import shutil
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import platformdirs

from bpb_core.errors import BadInput, BpbError, Notice
from bpb_core.version import __version__
from bpb_tasks.billiards.scene.model import WALLS, Scene
from bpb_tasks.billiards.truth.outcome import Event, Outcome, Segment
from bpb_tasks.simulators.analytic.motion import (
    Body,
    Motion,
    line_contact,
    moving_contact,
    pocket_entry,
    pocket_holding,
    time_for,
)
from bpb_tasks.simulators.analytic.roots import NO_ROOT, Number, sqrt

JIT_MARK = b"@jit"
"""How a module's compiled functions are marked; the modules holding it are hashed."""
ENTRY_POINTS = ("run_arrays", "run_many_arrays", "copy_masks")
"""The compiled functions Python calls; the kernel is cached when numba holds all three."""
PYTHON_SECONDS_PER_RUN = 2e-4
"""The Python engine's CPU time per simulated scene or perturbed copy, besides its events."""
PYTHON_SECONDS_PER_EVENT = 1e-4
"""The Python engine's CPU time per event."""
COMPILE_SECONDS = 20.0
"""The CPU time numba takes to build the kernel's entry points."""


class KernelNotice(Notice):
    """Something about the compiled kernel the user should know: it is being built, or it
    cannot be cached or loaded and bpb goes on without (the Python engine, or uncached code)."""


def sources_hash() -> str:
    """SHA-256 over the paths and contents of bpb_tasks' compiled modules, in path order."""
    root = Path(__file__).parents[2]
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        data = path.read_bytes()
        if JIT_MARK in data:
            digest.update(path.relative_to(root).as_posix().encode() + b"\0")
            digest.update(hashlib.sha256(data).digest())
    return digest.hexdigest()


def cache_folder() -> Path:
    """bpb's own numba cache folder: ``<user cache>/numba/<version>-<sources hash>``."""
    base = Path(platformdirs.user_cache_dir("bpb"))
    return base / "numba" / f"{__version__}-{sources_hash()[:16]}"


def numba_cache_dir(environ: Mapping[str, str]) -> Path:
    """The folder numba caches in given ``environ``: ``NUMBA_CACHE_DIR``, else bpb's own."""
    given = environ.get("NUMBA_CACHE_DIR")
    return Path(given) if given else cache_folder()


def is_cached(folder: Path) -> bool:
    """Whether ``folder`` holds an index of each of the kernel's :data:`ENTRY_POINTS`."""
    try:
        return all(any(folder.rglob(f"*.{name}-*.nbi")) for name in ENTRY_POINTS)
    except OSError:
        return False


def python_seconds(runs: int, events: float) -> float:
    """The Python engine's estimated CPU time for ``runs`` simulations of ``events`` each."""
    return runs * (PYTHON_SECONDS_PER_RUN + events * PYTHON_SECONDS_PER_EVENT)


def use_kernel(engine: str, available: bool, cached: bool, spent: float, seconds: float) -> bool:
    """Whether a batch the Python engine would take ``seconds`` for (:func:`python_seconds`)
    takes the compiled kernel.

    ``engine`` is ``"kernel"``, ``"python"`` or ``"auto"``; ``available``: numba is installed
    and the numbers are float64; ``cached``: the kernel is cached or already loaded;
    ``spent``: the Python engine's estimated CPU seconds so far in this simulator. ``auto``
    builds the kernel only once the Python engine's estimated time, with this batch, would
    reach the build's, so a command smaller than that never builds it."""
    if engine == "python" or not available:
        return False
    if engine == "kernel" or cached:
        return True
    return spent + seconds >= COMPILE_SECONDS


def note(text: str) -> None:
    """Say ``text`` as a :class:`KernelNotice` (a ``note:`` line from the CLI)."""
    with contextlib.suppress(KernelNotice):  # warnings made errors: a note must not stop it
        warnings.warn(text, KernelNotice, stacklevel=3)


@dataclass(frozen=True)
class Numeric:
    """A number system for the simulator.

    Attributes:
        name: ``float64`` or ``mpmath<digits>``.
        num: Lifts a Python float (exactly) into the backend.
        time_tol: Root refinement stops when the bracket is this narrow (seconds).
        max_iter: Upper bound on refinement iterations per root.
        speed_tol: Two touching balls whose approach speed is at most this fraction of the sum
            of their speeds do not collide: the exchange would be lost in the rounding of the
            speeds (the backend's relative precision, with a margin).
    """

    name: str
    num: Callable[[float], Number]
    time_tol: Number
    max_iter: int
    speed_tol: Number


FLOAT64 = Numeric("float64", float, 1e-15, 200, 1e-15)


def backend(precision: str | int | None) -> Numeric:
    """The backend named by ``precision``: ``None``/``"float64"``, or a digit count for mpmath
    (that many significant decimal digits, on a private mpmath context: the global
    ``mpmath.mp`` precision is left untouched)."""
    if precision is None or precision == "float64":
        return FLOAT64
    try:
        digits = int(precision)
    except ValueError:
        digits = 0
    if digits < 20:
        raise BadInput(f"--precision: expected 'float64' or a digit count >= 20, got {precision!r}")
    import mpmath

    ctx = mpmath.MPContext()
    ctx.dps = digits
    tol = ctx.mpf(10) ** (-(digits - 8))
    return Numeric(f"mpmath{digits}", ctx.mpf, tol, 400, tol)


BALL, WALL, POCKET, STOP = 0, 1, 2, 3
TOP, BOTTOM, LEFT, RIGHT = 0, 1, 2, 3


class Predictor:
    """Table geometry, the bodies and the event queue, with every prediction rule: when will
    each ball next stop, hit a wall, enter a pocket or touch another ball?

    Queue entries are ``(time, kind, index, other, version, other_version)`` tuples, so the heap
    orders simultaneous events by kind and then by ball (lowest first); an entry is stale when a
    ball's version has moved on since it was queued.
    """

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
        (:func:`use_kernel`); the first time,
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
        from bpb_tasks.simulators.analytic.kernel import CACHE, kernel_failure

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
            from bpb_tasks.simulators.analytic.kernel import kernel_outcome

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
        (:func:`~bpb_tasks.simulators.analytic.kernel.outcomes_many`: outcomes without motion
        pieces, ``segments`` empty), else :meth:`run` on each."""
        if scenes and self.takes_kernel(scenes[0], len(scenes)):
            from bpb_tasks.simulators.analytic.kernel import outcomes_many

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
