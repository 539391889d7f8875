"""The compiled event kernel: the analytic engine's event loop on arrays, compiled by numba.

Same conventions, same processing order and the same float64 operations as
:mod:`bpb_tasks.simulators.analytic.engine` (the reference, which stays the fallback without numba
and the only backend for mpmath). :func:`run_arrays` simulates one scene given as arrays and
returns its event log, motion pieces and final state as arrays:

* ``events``: rows ``(t, kind, a, b, wall, xa, ya, xb, yb)`` with ``a``/``b`` ball indices
  (``b = -1`` for one-ball events), ``wall`` the TOP/BOTTOM/LEFT/RIGHT index or ``-1``;
* ``pieces``: rows ``(index, t0, x, y, vx, vy)`` in the order the reference appends them;
* ``final``: rows ``(x, y, alive, end)`` at the horizon (``end``: the pocketing time, else the
  horizon);
* ``status``: 0, or 1 when the event budget was exceeded.

Its Python side takes scenes in and gives outcomes out: :func:`kernel_outcome` simulates one
:class:`~bpb_tasks.billiards.scene.model.Scene` with :func:`run_arrays` and builds the same
:class:`~bpb_tasks.billiards.truth.outcome.Outcome` the reference engine does;
:func:`outcomes_many` is the batch API behind ``AnalyticSimulator.run_many``: many scenes in one
compiled call, their outcomes without motion pieces; the stability copies take
:func:`run_batch`'s arrays. :func:`kernel_failure` loads (or builds) the kernel's entry points, or
says why numba could not.

A ball is a row of the float array ``st`` (columns :data:`X` .. :data:`WALL_T`) plus its version
and alive flag in the int array ``iv``; table constants are the float array ``prm`` (columns
:data:`DECEL` .. :data:`RECORD`). Queue entries are the reference's
``(time, kind, index, other, version, other_version)`` tuples in a list kept as a heap, so events
pop in the same order. The closed forms and root finding are the plain functions of
:mod:`~bpb_tasks.simulators.analytic.motion` and :mod:`~bpb_tasks.simulators.analytic.roots` that
the Python engine runs too, made callable from compiled code (``register_jitable``, with
``roots.sqrt`` compiled as ``math.sqrt``), so the kernel reproduces the Python engine's float64
results operation for operation.

Without numba the kernel's functions run as plain Python (slowly), which keeps the module
importable and testable. This is the one module that imports numba; it first points
``NUMBA_CACHE_DIR`` at bpb's cache folder unless the user set it
(:func:`~bpb_tasks.simulators.analytic.engine.cache_folder`).
"""

from __future__ import annotations

import heapq
import math
import os
from collections.abc import Callable, Sequence
from operator import attrgetter
from typing import Any, TypeVar

import numpy as np

from bpb_tasks.billiards.scene.model import WALLS, Ball, Scene
from bpb_tasks.billiards.truth.outcome import Event, Outcome, Segment
from bpb_tasks.simulators.analytic import motion, roots
from bpb_tasks.simulators.analytic.engine import (
    FLOAT64,
    KIND_NAMES,
    SimulationError,
    cache_folder,
    note,
)
from bpb_tasks.simulators.analytic.motion import (
    heading,
    line_contact,
    moving_contact,
    pocket_entry,
    pocket_holding,
    time_for,
)
from bpb_tasks.simulators.analytic.roots import NO_ROOT, Number

F = TypeVar("F", bound=Callable[..., Any])
TIME_TOL = FLOAT64.time_tol
SPEED_TOL = FLOAT64.speed_tol
MAX_ITER = FLOAT64.max_iter

if not os.environ.get("NUMBA_CACHE_DIR"):  # numba reads it as it is imported
    os.environ["NUMBA_CACHE_DIR"] = str(cache_folder())
_numba: Any
try:  # numba is an optional extra (``pip install 'bpb[fast]'``)
    import numba as _numba
except ImportError:
    _numba = None
except Exception as exc:  # an install numba cannot load itself in
    note(f"numba could not be imported ({type(exc).__name__}: {exc}); using the Python engine")
    _numba = None
HAVE_NUMBA = _numba is not None


def _cacheable() -> bool:
    """Whether numba finds a folder it can write its cache in (not on a read-only install
    without a writable home or cache folder: the kernel is then compiled in memory by each
    command that uses it, said once)."""
    try:
        _numba.njit(cache=True)(_cacheable)
    except RuntimeError as exc:  # "cannot cache function ...: no locator available"
        note(f"numba cannot cache the physics kernel ({exc}); each command compiles it anew")
        return False
    return True


CACHE = HAVE_NUMBA and _cacheable()


def jit(func: F) -> F:
    """Compile ``func`` with numba (cached on disk when it can be) when it is installed; else
    return it."""
    if _numba is None:
        return func
    try:
        return _numba.njit(cache=CACHE)(func)  # type: ignore[no-any-return]
    except RuntimeError:  # no cache folder for this module's folder alone: in memory
        return _numba.njit(func)  # type: ignore[no-any-return]


if _numba is not None:  # what jitted code calls of the plain modules, compiled where called
    from numba.extending import overload, register_jitable

    @overload(roots.sqrt)
    def _sqrt(x: float) -> Callable[[float], float]:
        def compiled(x: float) -> float:  # its parameters as ``roots.sqrt``'s, annotations too
            return math.sqrt(x)

        return compiled

    for _plain in (
        roots.horner,
        roots.derivative,
        roots.refine,
        roots.quadratic_splits,
        roots.critical_points,
        roots.first_contact,
        motion.time_for,
        motion.line_contact,
        motion.pocket_entry,
        motion.pocket_holding,
        motion.point_segment_gap2,
        motion.moving_contact,
    ):
        register_jitable(_plain)
    register_jitable(inline="always")(motion.heading)  # called per velocity change: inlined

X, Y, T0, SPEED, UX, UY, TSTOP, WALL_T = range(8)
VERSION, ALIVE = 0, 1
DECEL, HALF, CONTACT2, TWO_R, MARGIN, XMIN, XMAX, YMIN, YMAX, REST, POCKET_R = range(11)
HORIZON, RECORD = 11, 12  # a run's own: its end (no later event is queued), pieces kept
BALL, WALL, POCKET, STOP = 0, 1, 2, 3
TOP, BOTTOM, LEFT, RIGHT = 0, 1, 2, 3
INF = math.inf
Arr = Any  # a numpy array (numba has no static types for mypy)


@jit
def set_velocity(st: Arr, prm: Arr, i: int, t: float, vx: float, vy: float) -> None:
    st[i, T0] = t
    st[i, SPEED], st[i, UX], st[i, UY], st[i, TSTOP] = heading(t, vx, vy, prm[DECEL])


@jit
def state(st: Arr, prm: Arr, i: int, t: float) -> tuple[float, float, float]:
    speed = st[i, SPEED]
    if speed == 0:
        return st[i, X], st[i, Y], speed
    tstop = st[i, TSTOP]
    tau = (t if t < tstop else tstop) - st[i, T0]
    s = speed * tau - prm[HALF] * tau * tau
    now = speed - prm[DECEL] * tau if t < tstop else speed * 0
    return st[i, X] + st[i, UX] * s, st[i, Y] + st[i, UY] * s, now


@jit
def advance(st: Arr, prm: Arr, i: int, t: float) -> None:
    x, y, speed = state(st, prm, i, t)
    st[i, X], st[i, Y] = x, y
    set_velocity(st, prm, i, t, st[i, UX] * speed, st[i, UY] * speed)


@jit
def push(prm: Arr, queue: Any, t: float, kind: int, i: int, k: int, ver: int, other: int) -> None:
    if t <= prm[HORIZON]:  # a later event cannot fire in this run
        heapq.heappush(queue, (t, kind, i, k, ver, other))


@jit
def predict_single(st: Arr, iv: Arr, prm: Arr, pockets: Arr, queue: Any, i: int) -> None:
    st[i, WALL_T] = INF
    if st[i, SPEED] == 0:
        return
    far = INF
    if prm[DECEL] > 0:
        push(prm, queue, st[i, TSTOP], STOP, i, 0, iv[i, VERSION], 0)
        far = st[i, SPEED] * st[i, SPEED] / (2 * prm[DECEL])
    x, y, ux, uy = st[i, X], st[i, Y], st[i, UX], st[i, UY]
    if uy != 0:
        if uy > 0:
            predict_wall(st, iv, prm, queue, i, TOP, (prm[YMAX] - y) / uy, far)
        else:
            predict_wall(st, iv, prm, queue, i, BOTTOM, (y - prm[YMIN]) / -uy, far)
    if ux != 0:
        if ux > 0:
            predict_wall(st, iv, prm, queue, i, RIGHT, (prm[XMAX] - x) / ux, far)
        else:
            predict_wall(st, iv, prm, queue, i, LEFT, (x - prm[XMIN]) / -ux, far)
    predict_pocket(st, iv, prm, pockets, queue, i, far)


@jit
def pocket_at_start(st: Arr, iv: Arr, prm: Arr, pockets: Arr, queue: Any, i: int) -> None:
    k = pocket_holding(st[i, X], st[i, Y], pockets, prm[POCKET_R])
    if k >= 0:
        push(prm, queue, st[i, T0], POCKET, i, k, iv[i, VERSION], 0)


@jit
def predict_wall(
    st: Arr, iv: Arr, prm: Arr, queue: Any, i: int, wall: int, gap: float, far: float
) -> None:
    gap = gap if gap > 0 else gap * 0
    if gap < far:
        t = st[i, T0] + time_for(prm[DECEL], st[i, SPEED], gap)
        push(prm, queue, t, WALL, i, wall, iv[i, VERSION], 0)
        st[i, WALL_T] = t if t < st[i, WALL_T] else st[i, WALL_T]


@jit
def predict_pocket(
    st: Arr, iv: Arr, prm: Arr, pockets: Arr, queue: Any, i: int, far: float
) -> None:
    x, y, ux, uy = st[i, X], st[i, Y], st[i, UX], st[i, UY]
    best, pocket = pocket_entry(x, y, ux, uy, pockets, prm[POCKET_R], far)
    if best != NO_ROOT:
        t = st[i, T0] + (time_for(prm[DECEL], st[i, SPEED], best) if best > 0 else best)
        push(prm, queue, t, POCKET, i, pocket, iv[i, VERSION], 0)


@jit
def predict_pair(st: Arr, iv: Arr, prm: Arr, queue: Any, p: int, q: int, t: float) -> None:
    if p > q:
        p, q = q, p
    if (st[p, SPEED] == 0 or st[p, TSTOP] <= t) and (st[q, SPEED] == 0 or st[q, TSTOP] <= t):
        return
    px, py, ps = state(st, prm, p, t)
    qx, qy, qs = state(st, prm, q, t)
    if ps == 0 and qs == 0:
        return
    if ps == 0 or qs == 0:
        if qs == 0:
            mx, my, ms, mover, rx, ry = px, py, ps, p, qx, qy
        else:
            mx, my, ms, mover, rx, ry = qx, qy, qs, q, px, py
        s = line_contact(mx - rx, my - ry, st[mover, UX], st[mover, UY], prm[CONTACT2])
        if s == NO_ROOT:
            return
        far = ms * ms / (2 * prm[DECEL]) if prm[DECEL] > 0 else INF
        if s < far:
            tau = time_for(prm[DECEL], ms, s) if s > 0 else s
            push(prm, queue, t + tau, BALL, p, q, iv[p, VERSION], iv[q, VERSION])
        return
    tau = moving_pair(st, prm, p, q, t, px, py, qx, qy, ps, qs)
    if tau != NO_ROOT:
        push(prm, queue, t + tau, BALL, p, q, iv[p, VERSION], iv[q, VERSION])


@jit
def moving_pair(
    st: Arr,
    prm: Arr,
    p: int,
    q: int,
    t: float,
    px: float,
    py: float,
    qx: float,
    qy: float,
    ps: float,
    qs: float,
) -> Number:
    """First contact time (from ``t``) of two moving balls; :data:`NO_ROOT` if none."""
    span = min(st[p, TSTOP], st[q, TSTOP], st[p, WALL_T], st[q, WALL_T]) - t
    if span < 0:
        return NO_ROOT
    h = prm[HALF]
    return moving_contact(
        (px - qx, py - qy),
        (st[p, UX] * ps - st[q, UX] * qs, st[p, UY] * ps - st[q, UY] * qs),
        ((st[q, UX] - st[p, UX]) * h, (st[q, UY] - st[p, UY]) * h),
        span,
        prm[TWO_R],
        prm[MARGIN],
        TIME_TOL,
        MAX_ITER,
    )


@jit
def predict_pairs(st: Arr, iv: Arr, prm: Arr, queue: Any, b: int, t: float, skip: int) -> None:
    moving = st[b, SPEED] > 0
    x, y, ux, uy, contact2 = st[b, X], st[b, Y], st[b, UX], st[b, UY], prm[CONTACT2]
    for o in range(st.shape[0]):
        if o in (b, skip) or iv[o, ALIVE] == 0:
            continue
        if st[o, SPEED] == 0:
            if not moving:
                continue
            dx, dy = x - st[o, X], y - st[o, Y]
            along = ux * dx + uy * dy
            if along >= 0:
                continue
            c = dx * dx + dy * dy - contact2
            if c > 0 and along * along <= c:
                continue
        predict_pair(st, iv, prm, queue, b, o, t)


@jit
def _changed(
    st: Arr, iv: Arr, prm: Arr, pieces: Any, i: int, t: float, vx: float, vy: float
) -> None:
    set_velocity(st, prm, i, t, vx, vy)
    iv[i, VERSION] += 1
    if prm[RECORD]:
        pieces.append((float(i), t, st[i, X], st[i, Y], vx, vy))


@jit
def _log(events: Any, st: Arr, t: float, kind: int, a: int, b: int, wall: int) -> None:
    xb = st[b, X] if b >= 0 else 0.0
    yb = st[b, Y] if b >= 0 else 0.0
    events.append((t, float(kind), float(a), float(b), float(wall), st[a, X], st[a, Y], xb, yb))


@jit
def _collide(
    st: Arr, iv: Arr, prm: Arr, queue: Any, events: Any, pieces: Any, p: int, q: int, t: float
) -> bool:
    px, py, ps = state(st, prm, p, t)
    qx, qy, qs = state(st, prm, q, t)
    nx, ny = qx - px, qy - py
    norm = np.sqrt(nx * nx + ny * ny)
    nx, ny = nx / norm, ny / norm
    pvx, pvy, qvx, qvy = st[p, UX] * ps, st[p, UY] * ps, st[q, UX] * qs, st[q, UY] * qs
    vn = (pvx - qvx) * nx + (pvy - qvy) * ny
    if not vn > SPEED_TOL * (ps + qs):  # as engine._Simulation.collide
        return False
    st[p, X], st[p, Y], st[q, X], st[q, Y] = px, py, qx, qy
    _changed(st, iv, prm, pieces, p, t, pvx - vn * nx, pvy - vn * ny)
    _changed(st, iv, prm, pieces, q, t, qvx + vn * nx, qvy + vn * ny)
    _log(events, st, t, BALL, p, q, -1)
    return True


@jit
def _loop(
    st: Arr,
    iv: Arr,
    prm: Arr,
    pockets: Arr,
    queue: Any,
    events: Any,
    pieces: Any,
    ended: Arr,
    horizon: float,
    max_events: int,
) -> int:
    count = 0
    while len(queue) > 0 and queue[0][0] <= horizon:
        t, kind, i, k, ver_i, ver_k = heapq.heappop(queue)
        if iv[i, VERSION] != ver_i or iv[i, ALIVE] == 0:
            continue
        if kind == BALL:
            if iv[k, VERSION] != ver_k or iv[k, ALIVE] == 0:
                continue
            if not _collide(st, iv, prm, queue, events, pieces, i, k, t):
                continue
            predict_single(st, iv, prm, pockets, queue, i)
            predict_pairs(st, iv, prm, queue, i, t, -1)
            predict_single(st, iv, prm, pockets, queue, k)
            predict_pairs(st, iv, prm, queue, k, t, i)
        elif kind == WALL:  # wall ``k``
            advance(st, prm, i, t)
            vx, vy = st[i, UX] * st[i, SPEED], st[i, UY] * st[i, SPEED]
            if k in (TOP, BOTTOM):
                st[i, Y] = prm[YMAX] if k == TOP else prm[YMIN]
                vy = -vy * prm[REST]
            else:
                st[i, X] = prm[XMAX] if k == RIGHT else prm[XMIN]
                vx = -vx * prm[REST]
            _changed(st, iv, prm, pieces, i, t, vx, vy)
            _log(events, st, t, WALL, i, -1, k)
            predict_single(st, iv, prm, pockets, queue, i)
            predict_pairs(st, iv, prm, queue, i, t, -1)
        elif kind == POCKET:
            advance(st, prm, i, t)
            iv[i, ALIVE] = 0
            iv[i, VERSION] += 1
            ended[i] = t
            _log(events, st, t, POCKET, i, -1, -1)
        else:
            advance(st, prm, i, t)
            zero = st[i, SPEED] * 0
            _changed(st, iv, prm, pieces, i, t, zero, zero)
            _log(events, st, t, STOP, i, -1, -1)
            predict_pairs(st, iv, prm, queue, i, t, -1)
        count += 1
        if count > max_events:
            return 1
    return 0


@jit
def run_arrays(
    pos: Arr, vel: Arr, prm: Arr, pockets: Arr, horizon: float, max_events: int
) -> tuple[Arr, Arr, Arr, int]:
    """Simulate one scene (see the module docstring); ``pos``/``vel`` are ``(n, 2)`` arrays of
    the balls sorted by id and ``prm`` the table constants (:data:`DECEL` .. :data:`POCKET_R`)."""
    work = buffers(pos.shape[0])
    status = run_into(work, pos, vel, prm, pockets, horizon, max_events, True)
    return _table(work[4], 9), _table(work[5], 6), work[6], status


@jit
def buffers(n: int) -> tuple[Arr, Arr, Arr, Any, Any, Any, Arr, Arr]:
    """The working arrays and lists of a run of ``n`` balls: ``(st, iv, ended, queue, events,
    pieces, final, constants)``; :func:`run_into` resets them, so many runs can share one
    set."""
    queue = [(0.0, 0, 0, 0, 0, 0)]
    events = [(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)]
    pieces = [(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)]
    st, iv, ended = np.zeros((n, 8)), np.zeros((n, 2), dtype=np.int64), np.zeros(n)
    return st, iv, ended, queue, events, pieces, np.zeros((n, 4)), np.zeros(RECORD + 1)


@jit
def run_into(
    work: tuple[Arr, Arr, Arr, Any, Any, Any, Arr, Arr],
    pos: Arr,
    vel: Arr,
    table: Arr,
    pockets: Arr,
    horizon: float,
    max_events: int,
    record: bool,
) -> int:
    """Run the balls ``pos``/``vel`` on the table ``table`` in the :func:`buffers` ``work``,
    leaving the events, the pieces of motion (when ``record``) and the final rows there;
    returns the status."""
    st, iv, ended, queue, events, pieces, final, prm = work
    prm[:HORIZON] = table[:HORIZON]
    prm[HORIZON], prm[RECORD] = horizon, 1.0 if record else 0.0
    n = pos.shape[0]
    st[:] = 0.0
    st[:, 0] = pos[:, 0]
    st[:, 1] = pos[:, 1]
    iv[:] = 0
    iv[:, ALIVE] = 1
    ended[:] = horizon
    queue.clear()
    events.clear()
    pieces.clear()
    for i in range(n):
        set_velocity(st, prm, i, 0.0, vel[i, 0], vel[i, 1])
        if prm[RECORD]:
            pieces.append((float(i), 0.0, st[i, X], st[i, Y], vel[i, 0], vel[i, 1]))
    for i in range(n):
        if st[i, SPEED] > 0:
            predict_single(st, iv, prm, pockets, queue, i)
        else:
            pocket_at_start(st, iv, prm, pockets, queue, i)
    for i in range(n):
        if st[i, SPEED] > 0:
            predict_pairs(st, iv, prm, queue, i, 0.0, -1)
    status = _loop(st, iv, prm, pockets, queue, events, pieces, ended, horizon, max_events)
    final[:] = 0.0
    for i in range(n):
        if iv[i, ALIVE] == 1:
            x, y, _ = state(st, prm, i, horizon)
            final[i, 0], final[i, 1], final[i, 2] = x, y, 1.0
        final[i, 3] = ended[i]
    return status


@jit
def _table(rows: Any, width: int) -> Arr:
    out = np.empty((len(rows), width))
    for r in range(len(rows)):
        row = rows[r]
        for c in range(width):
            out[r, c] = row[c]
    return out


@jit
def run_many_arrays(
    pos: Arr, vel: Arr, starts: Arr, prm: Arr, pockets: Arr, horizons: Arr, max_events: int
) -> tuple[Arr, Arr, Arr]:
    """Simulate many scenes sharing one table in a single call: scene ``s`` holds balls
    ``starts[s]:starts[s + 1]`` of ``pos``/``vel``. Returns per-ball final rows (as
    :func:`run_arrays`), per-scene statuses, and the event tables concatenated with a leading
    scene column. Scenes of as many balls as the one before share its working arrays
    (:func:`buffers`), and each scene's events go straight from the loop's rows into the one
    table: no pieces of motion, and no array per scene."""
    scenes = starts.shape[0] - 1
    final = np.zeros((pos.shape[0], 4))
    status = np.zeros(scenes, dtype=np.int64)
    events = np.empty((max(16, 4 * scenes), 10))
    row = 0
    n = 0
    work = buffers(0)
    for s in range(scenes):
        a, b = starts[s], starts[s + 1]
        if b - a != n:
            n = b - a
            work = buffers(n)
        status[s] = run_into(work, pos[a:b], vel[a:b], prm, pockets, horizons[s], max_events, False)
        final[a:b] = work[6]
        rows = work[4]
        if row + len(rows) > events.shape[0]:
            grown = np.empty((max(2 * events.shape[0], row + len(rows)), 10))
            grown[:row] = events[:row]
            events = grown
        for r in range(len(rows)):
            event = rows[r]
            events[row, 0] = s
            for c in range(9):
                events[row, c + 1] = event[c]
            row += 1
    return final, status, events[:row]


def table_params(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's table constants (:data:`DECEL` .. :data:`POCKET_R`,
    the same arithmetic as the reference ``Predictor``) and pocket centres of ``scene``."""
    table, phys, pockets = scene.table, scene.physics, scene.pockets
    radius = phys.ball_radius
    decel = phys.mu * phys.g
    prm = np.array(
        [
            decel,
            decel / 2,
            4 * radius * radius,
            2 * radius,
            1e-9,
            radius,
            table.width - radius,
            radius,
            table.height - radius,
            phys.wall_restitution,
            pockets.radius,
        ]
    )
    return prm, np.array(pockets.centers, dtype=float).reshape(-1, 2)


def scene_arrays(scene: Scene) -> tuple[list[int], np.ndarray, np.ndarray]:
    """Ball ids (sorted), positions and velocities of ``scene``."""
    balls = sorted(scene.balls, key=attrgetter("id"))
    pos = np.array([b.pos for b in balls], dtype=float).reshape(-1, 2)
    vel = np.array([b.vel for b in balls], dtype=float).reshape(-1, 2)
    return [b.id for b in balls], pos, vel


def kernel_failure(scene: Scene) -> str | None:
    """Load (or build) the kernel's entry points by running a ball at rest on ``scene``'s table
    through each as the real calls do: ``None`` when they run, else what went wrong (numba
    cannot read a cache file of them, say); numba keeps what it loaded, so the calls after this
    one take it."""
    from bpb_tasks.billiards.stability.annotation import perturbation_arrays
    from bpb_tasks.billiards.stability.kernel import copy_labels

    if not HAVE_NUMBA:
        return "numba could not be imported"
    table = scene.table  # one ball at rest mid-table: one event at most
    still = Ball.model_construct(id=0, pos=(table.width / 2, table.height / 2), vel=(0.0, 0.0))
    one = scene.model_copy(update={"balls": [still]})
    try:
        kernel_outcome(one, one.horizon, 10_000)
        run_batch([one], None, 10_000, check=False)
        ids, pos, vel = perturbation_arrays(one, 1e-4, 1)
        copy_labels(one, ids, pos, vel, 10_000)
    except Exception as exc:  # whatever numba raised: the kernel is not to be used
        return f"{type(exc).__name__}: {exc}"
    return None


def kernel_outcome(scene: Scene, horizon: float, max_events: int) -> Outcome:
    """Simulate ``scene`` to ``horizon`` with the kernel; the reference engine's Outcome."""
    ids, pos, vel = scene_arrays(scene)
    prm, pockets = table_params(scene)
    events, pieces, final, status = run_arrays(pos, vel, prm, pockets, float(horizon), max_events)
    if status:
        raise SimulationError(f"more than {max_events} events before t={float(horizon)}")
    decel = float(prm[0])
    rows = final.tolist()
    positions = {ids[i]: (r[0], r[1]) if r[2] else None for i, r in enumerate(rows)}
    per_ball: list[list[list[float]]] = [[] for _ in ids]
    for row in pieces.tolist():
        per_ball[int(row[0])].append(row)
    segments = {}
    for i, own in enumerate(per_ball):
        end = rows[i][3]
        segments[ids[i]] = tuple(
            Segment(
                p[1], own[j + 1][1] if j + 1 < len(own) else end, (p[2], p[3]), (p[4], p[5]), decel
            )
            for j, p in enumerate(own)
        )
    return Outcome(float(horizon), positions, _event_log(ids, events.tolist()), segments)


def _event_log(ids: Sequence[int], rows: list[list[float]]) -> tuple[Event, ...]:
    """The events of the kernel's event rows ``(t, kind, a, b, wall, xa, ya, xb, yb)``, whose
    balls ``a`` and ``b`` are indices into ``ids``."""
    log = []
    for t, kind, a, b, wall, xa, ya, xb, yb in rows:
        if b >= 0:
            log.append(Event(t, "ball", (ids[int(a)], ids[int(b)]), None, ((xa, ya), (xb, yb))))
        else:
            name = WALLS[int(wall)] if wall >= 0 else None
            log.append(Event(t, KIND_NAMES[int(kind)], (ids[int(a)],), name, ((xa, ya),)))
    return tuple(log)


def outcomes_many(
    scenes: Sequence[Scene], horizons: Sequence[float] | None = None, max_events: int = 100_000
) -> list[Outcome]:
    """The outcomes of many scenes (sharing table, physics and pockets) run to ``horizons``
    (default: their own) in one compiled call: final positions and events, and no motion
    pieces (``segments`` empty: nothing to draw from them).

    Raises:
        ValueError: The scenes do not share one table.
        SimulationError: A scene exceeded ``max_events``.
    """
    if not scenes:
        return []
    ends = [s.horizon for s in scenes] if horizons is None else list(horizons)
    ids, starts, final, _, events = run_batch(scenes, ends, max_events)
    rows = final.tolist()
    bounds = np.searchsorted(events[:, 0], np.arange(len(scenes) + 1)).tolist()  # in scene order
    event_rows = events[:, 1:].tolist()
    outcomes = []
    for k, (own, a, b) in enumerate(
        zip(ids, starts[:-1].tolist(), starts[1:].tolist(), strict=True)
    ):
        positions = {i: (r[0], r[1]) if r[2] else None for i, r in zip(own, rows[a:b], strict=True)}
        log = _event_log(own, event_rows[bounds[k] : bounds[k + 1]])
        outcomes.append(Outcome(float(ends[k]), positions, log, {}))
    return outcomes


def run_batch(
    scenes: Sequence[Scene], horizons: Sequence[float] | None, max_events: int, check: bool = True
) -> tuple[list[list[int]], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The kernel's raw batch results of ``scenes`` (sharing one table) run to ``horizons``
    (default: their own): per-scene ball ids, ball offsets, final rows, statuses and the event
    rows (scene index first).

    Raises:
        SimulationError: A scene exceeded ``max_events`` (when ``check``).
    """
    first = scenes[0]
    shape = (first.table, first.physics, first.pockets)
    if any(
        (s.table, s.physics, s.pockets) != shape
        for s in scenes
        if s.table is not first.table or s.physics is not first.physics
        or s.pockets is not first.pockets
    ):  # fmt: skip
        raise ValueError("outcomes_many: scenes must share table, physics and pockets")
    ordered = [sorted(s.balls, key=attrgetter("id")) for s in scenes]
    pos = np.array([b.pos for balls in ordered for b in balls], dtype=float).reshape(-1, 2)
    vel = np.array([b.vel for balls in ordered for b in balls], dtype=float).reshape(-1, 2)
    starts = np.cumsum([0] + [len(balls) for balls in ordered])
    ends = [s.horizon for s in scenes] if horizons is None else list(horizons)
    prm, pockets = table_params(first)
    final, status, events = run_many_arrays(
        pos, vel, starts, prm, pockets, np.array(ends, dtype=float), max_events
    )
    if check and status.any():
        raise SimulationError(f"scene {int(np.argmax(status))}: more than {max_events} events")
    return [[b.id for b in balls] for balls in ordered], starts, final, status, events
