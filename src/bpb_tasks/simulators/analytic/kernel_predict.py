"""Motion and event prediction of the compiled event kernel (reference:
:mod:`~bpb_tasks.simulators.analytic.motion` and :mod:`~bpb_tasks.simulators.analytic.prediction`).

A ball is a row of the float array ``st`` (columns :data:`X` .. :data:`WALL_T`) plus its version
and alive flag in the int array ``iv``; table constants are the float array ``prm`` (columns
:data:`DECEL` .. :data:`RECORD`). Queue entries are the reference's
``(time, kind, index, other, version, other_version)`` tuples in a list kept as a heap, so events
pop in the same order.
"""

from __future__ import annotations

import heapq
import math
from typing import Any

from bpb_tasks.simulators.analytic.kernel_roots import MAX_ITER, TIME_TOL, jit
from bpb_tasks.simulators.analytic.motion import (
    heading,
    line_contact,
    moving_contact,
    pocket_entry,
    pocket_holding,
    time_for,
)
from bpb_tasks.simulators.analytic.roots import NO_ROOT, Number

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
