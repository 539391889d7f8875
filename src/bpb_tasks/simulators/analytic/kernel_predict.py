"""Motion and event prediction of the compiled event kernel (reference:
:mod:`~bpb_tasks.simulators.analytic.motion` and :mod:`~bpb_tasks.simulators.analytic.prediction`).

A ball is a row of the float array ``st`` (columns :data:`X` .. :data:`WALL_T`) plus its version
and alive flag in the int array ``iv``; table constants are the float array ``prm`` (columns
:data:`DECEL` .. :data:`HORIZON`). Queue entries are the reference's
``(time, kind, index, other, version, other_version)`` tuples in a list kept as a heap, so events
pop in the same order.
"""

from __future__ import annotations

import heapq
import math
from typing import Any

from bpb_tasks.simulators.analytic.kernel_roots import NO_ROOT, first_contact, jit
from bpb_tasks.simulators.analytic.motion import point_segment_gap2

X, Y, T0, SPEED, UX, UY, TSTOP, WALL_T = range(8)
VERSION, ALIVE = 0, 1
DECEL, HALF, CONTACT2, TWO_R, MARGIN, XMIN, XMAX, YMIN, YMAX, REST, POCKET_R, POCKET_R2 = range(12)
HORIZON, RECORD = 12, 13  # a run's own: its end (no later event is queued), pieces kept
BALL, WALL, POCKET, STOP = 0, 1, 2, 3
TOP, BOTTOM, LEFT, RIGHT = 0, 1, 2, 3
INF = math.inf
Arr = Any  # a numpy array (numba has no static types for mypy)
gap2 = jit(point_segment_gap2)  # the reference's own code, compiled


@jit
def set_velocity(st: Arr, prm: Arr, i: int, t: float, vx: float, vy: float) -> None:
    st[i, T0] = t
    speed = math.sqrt(vx * vx + vy * vy)
    if speed > 0:
        st[i, SPEED], st[i, UX], st[i, UY] = speed, vx / speed, vy / speed
        st[i, TSTOP] = t + speed / prm[DECEL] if prm[DECEL] > 0 else INF
    else:
        st[i, SPEED], st[i, UX], st[i, UY], st[i, TSTOP] = speed * 0, speed * 0, speed * 0, t


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
def time_for(prm: Arr, speed: float, s: float) -> float:
    decel = prm[DECEL]
    if decel == 0:
        return float(s / speed)
    rest = speed * speed - 2 * decel * s
    return 2 * s / (speed + math.sqrt(rest if rest > 0 else rest * 0))


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
    x, y, r, r2 = st[i, X], st[i, Y], prm[POCKET_R], prm[POCKET_R2]
    for k in range(pockets.shape[0]):
        dx, dy = x - pockets[k, 0], y - pockets[k, 1]
        if -r <= dx <= r and dx * dx + dy * dy <= r2:
            push(prm, queue, st[i, T0], POCKET, i, k, iv[i, VERSION], 0)
            return


@jit
def predict_wall(
    st: Arr, iv: Arr, prm: Arr, queue: Any, i: int, wall: int, gap: float, far: float
) -> None:
    gap = gap if gap > 0 else gap * 0
    if gap < far:
        t = st[i, T0] + time_for(prm, st[i, SPEED], gap)
        push(prm, queue, t, WALL, i, wall, iv[i, VERSION], 0)
        st[i, WALL_T] = t if t < st[i, WALL_T] else st[i, WALL_T]


@jit
def predict_pocket(
    st: Arr, iv: Arr, prm: Arr, pockets: Arr, queue: Any, i: int, far: float
) -> None:
    best, found, pocket = 0.0, False, 0
    x, y, ux, uy = st[i, X], st[i, Y], st[i, UX], st[i, UY]
    r, r2 = prm[POCKET_R], prm[POCKET_R2]
    for k in range(pockets.shape[0]):
        dx, dy = x - pockets[k, 0], y - pockets[k, 1]
        along = ux * dx + uy * dy
        if along >= 0:
            if not (-r <= dx <= r and -r <= dy <= r and dx * dx + dy * dy <= r2):
                continue
            s = along * 0
        else:
            c = dx * dx + dy * dy - r2
            if c <= 0:
                s = c * 0
            elif along * along < c:
                continue
            else:
                s = c / (-along + math.sqrt(along * along - c))
        if s <= far and (not found or s < best):
            best, found, pocket = s, True, k
    if found:
        t = st[i, T0] + (time_for(prm, st[i, SPEED], best) if best > 0 else best)
        push(prm, queue, t, POCKET, i, pocket, iv[i, VERSION], 0)


@jit
def line_contact(dx: float, dy: float, ux: float, uy: float, radius2: float) -> float:
    """Reference ``motion.line_contact``; :data:`NO_ROOT` for ``None`` (distances are >= 0)."""
    b = ux * dx + uy * dy
    c = dx * dx + dy * dy - radius2
    if c <= 0:
        return b * 0 if b < 0 else NO_ROOT
    if b >= 0:
        return NO_ROOT
    disc = b * b - c
    if disc <= 0:
        return NO_ROOT
    return c / (-b + math.sqrt(disc))


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
            tau = time_for(prm, ms, s) if s > 0 else s
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
) -> float:
    """First contact time (from ``t``) of two moving balls; :data:`NO_ROOT` if none."""
    span = min(st[p, TSTOP], st[q, TSTOP], st[p, WALL_T], st[q, WALL_T]) - t
    if span < 0:
        return NO_ROOT
    vx, vy = st[p, UX] * ps - st[q, UX] * qs, st[p, UY] * ps - st[q, UY] * qs
    h = prm[HALF]
    ax, ay = (st[q, UX] - st[p, UX]) * h, (st[q, UY] - st[p, UY]) * h
    dx, dy = px - qx, py - qy
    ex = vx * span + ax * span * span  # the reference's cheap rejection
    ey = vy * span + ay * span * span
    bulge = math.sqrt(ax * ax + ay * ay) * span * span / 4
    limit = prm[TWO_R] * (1 + prm[MARGIN]) + bulge
    if gap2(dx, dy, ex, ey) > limit * limit:
        return NO_ROOT
    coeffs = (
        ax * ax + ay * ay,
        2 * (ax * vx + ay * vy),
        vx * vx + vy * vy + 2 * (ax * dx + ay * dy),
        2 * (vx * dx + vy * dy),
        dx * dx + dy * dy - prm[CONTACT2],
    )
    return first_contact(coeffs, span)


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
