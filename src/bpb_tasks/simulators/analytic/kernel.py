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
"""

from __future__ import annotations

import heapq
from typing import Any

import numpy as np

from bpb_tasks.simulators.analytic.kernel_predict import (
    ALIVE,
    BALL,
    BOTTOM,
    HORIZON,
    POCKET,
    RECORD,
    REST,
    RIGHT,
    SPEED,
    STOP,
    TOP,
    UX,
    UY,
    VERSION,
    WALL,
    XMAX,
    XMIN,
    YMAX,
    YMIN,
    Arr,
    X as _X,
    Y as _Y,
    advance,
    pocket_at_start,
    predict_pairs,
    predict_single,
    set_velocity,
    state,
)
from bpb_tasks.simulators.analytic.kernel_roots import SPEED_TOL, jit

__all__ = ["buffers", "run_arrays", "run_into", "run_many_arrays"]


@jit
def _changed(
    st: Arr, iv: Arr, prm: Arr, pieces: Any, i: int, t: float, vx: float, vy: float
) -> None:
    set_velocity(st, prm, i, t, vx, vy)
    iv[i, VERSION] += 1
    if prm[RECORD]:
        pieces.append((float(i), t, st[i, _X], st[i, _Y], vx, vy))


@jit
def _log(events: Any, st: Arr, t: float, kind: int, a: int, b: int, wall: int) -> None:
    xb = st[b, _X] if b >= 0 else 0.0
    yb = st[b, _Y] if b >= 0 else 0.0
    events.append((t, float(kind), float(a), float(b), float(wall), st[a, _X], st[a, _Y], xb, yb))


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
    st[p, _X], st[p, _Y], st[q, _X], st[q, _Y] = px, py, qx, qy
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
                st[i, _Y] = prm[YMAX] if k == TOP else prm[YMIN]
                vy = -vy * prm[REST]
            else:
                st[i, _X] = prm[XMAX] if k == RIGHT else prm[XMIN]
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
    the balls sorted by id and ``prm`` the table constants of ``kernel_predict``."""
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
            pieces.append((float(i), 0.0, st[i, _X], st[i, _Y], vel[i, 0], vel[i, 1]))
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
