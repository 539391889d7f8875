"""The compiled parts of the stability annotation (called from
:mod:`bpb_tasks.billiards.stability_batch`).

* :func:`tally_copies` runs each perturbed copy through the kernel and folds its event rows and
  final state into the tally at once: label bit masks per copy (cue contacts, cue walls,
  pocketed balls; one bit per ball index or wall), XORed against the nominal masks, and the
  largest distance of a ball from its nominal final position. No per-copy table is built.
* :func:`perturb` draws the perturbed copies' random angles and builds their positions and
  velocities (:func:`~bpb_tasks.billiards.stability.perturbation_arrays` without a Python call
  per draw or the numpy calls).
* :func:`horizon_event_gap` is the horizon gap of
  :mod:`bpb_tasks.billiards.stability_margins` read off a kernel run's event rows.
* :func:`pair_margin_arrays` is the near-miss margin and the overlap of
  :mod:`bpb_tasks.billiards.stability_margins` (the reference, ``pair_margins``) with the same
  float64 operations in the same order.
"""

from __future__ import annotations

import math

import numpy as np

from bpb_tasks.billiards.stability_draws import random_draws
from bpb_tasks.simulators.analytic.kernel import run_rows
from bpb_tasks.simulators.analytic.kernel_predict import BALL, STOP, WALL, Arr
from bpb_tasks.simulators.analytic.kernel_roots import Poly, critical_points, horner, jit

TWO_PI = 2 * math.pi


@jit
def tally_copies(
    pos: Arr,
    vel: Arr,
    n: int,
    prm: Arr,
    pockets: Arr,
    horizon: float,
    max_events: int,
    cue: int,
    reference: Arr,
    nominal: Arr,
) -> tuple[Arr, Arr, int, float, int]:
    """Tally the copies of ``n`` balls stacked in ``pos``/``vel`` (``(copies * n, 2)``).

    ``cue`` is the cue ball's index (-1 without one), ``reference`` the nominal
    ``(contacts, walls, pocketed)`` masks and ``nominal`` the ``(n, 2)`` nominal final positions
    (NaN for pocketed balls). Returns the flip count per label group, the union of flipped bits
    per group, the number of finished copies with any flip, the Q3 spread, and the number of
    copies left unfinished after ``max_events`` events, which count in none of the others
    (their labels and final positions are unknown;
    :meth:`~bpb_tasks.billiards.stability_batch.Tally.add_unfinished` says how they count).
    """
    copies = pos.shape[0] // n if n else 0
    counts = np.zeros(3, dtype=np.int64)
    unions = np.zeros(3, dtype=np.int64)
    masks = np.zeros(3, dtype=np.int64)
    any_flip = 0
    spread = 0.0
    unfinished = 0
    for c in range(copies):
        a, b = c * n, (c + 1) * n
        events, _, final, status = run_rows(pos[a:b], vel[a:b], prm, pockets, horizon, max_events)
        if status != 0:
            unfinished += 1
            continue
        masks[:] = 0
        if cue >= 0:
            for row in events:
                kind, p, q, wall = row[1], int(row[2]), int(row[3]), row[4]
                if kind == BALL and (p == cue or q == cue):
                    masks[0] |= np.int64(1) << (q if p == cue else p)
                elif kind == WALL and p == cue and wall >= 0:
                    masks[1] |= np.int64(1) << int(wall)
        for j in range(n):
            if final[j, 2] == 0:
                masks[2] |= np.int64(1) << j
            elif not np.isnan(nominal[j, 0]):
                gap = np.hypot(final[j, 0] - nominal[j, 0], final[j, 1] - nominal[j, 1])
                spread = max(spread, gap)
        flipped = False
        for g in range(3):
            xor = masks[g] ^ reference[g]
            if xor != 0:
                counts[g] += 1
                unions[g] |= xor
                flipped = True
        any_flip += flipped
    return counts, unions, any_flip, spread, unfinished


@jit
def perturb(
    key: Arr, samples: int, centres: Arr, velocities: Arr, delta: float, cue: int, kick: float
) -> tuple[Arr, Arr]:
    """The ``(samples, n, 2)`` positions and velocities of the copies of ``n`` balls at
    ``centres`` moving at ``velocities``, from the draws of a generator seeded with ``key``
    (:func:`~bpb_tasks.billiards.stability_draws.random_draws`), ``n + 1`` per copy: ball ``j``
    moved by ``delta`` at angle ``2 pi`` times draw ``j``, the cue ball (index ``cue``, -1
    without one) kicked by ``kick`` at angle ``2 pi`` times draw ``n``. The numpy operations of
    ``perturbation_arrays`` element by element."""
    n = centres.shape[0]
    angles = random_draws(key, samples * (n + 1))
    pos = np.empty((samples, n, 2))
    vel = np.empty((samples, n, 2))
    for k in range(samples):
        row = k * (n + 1)
        for j in range(n):
            angle = angles[row + j] * TWO_PI
            pos[k, j, 0] = centres[j, 0] + delta * np.cos(angle)
            pos[k, j, 1] = centres[j, 1] + delta * np.sin(angle)
            vel[k, j, 0], vel[k, j, 1] = velocities[j, 0], velocities[j, 1]
        if cue >= 0:
            angle = angles[row + n] * TWO_PI
            vel[k, cue, 0] += kick * np.cos(angle)
            vel[k, cue, 1] += kick * np.sin(angle)
    return pos, vel


@jit
def horizon_event_gap(
    pos: Arr, vel: Arr, prm: Arr, pockets: Arr, horizon: float, end: float, max_events: int
) -> tuple[float, bool, int]:
    """The smallest ``|t - horizon|`` over the ball, wall and pocket events (not stops) of the
    balls ``pos``/``vel`` run to ``end``, whether there is such an event, and the run's status
    (1: over ``max_events`` events)."""
    events, _, _, status = run_rows(pos, vel, prm, pockets, end, max_events)
    best = np.inf
    found = False
    for row in events:
        if row[1] != STOP:
            gap = abs(row[0] - horizon)
            best = gap if not found or gap < best else best
            found = True
    return best, found, status


@jit
def pair_margin_arrays(
    rows: Arr, balls: int, touched: Arr, moving: Arr, radius: float, tolerance: float
) -> tuple[float, bool, float, bool]:
    """:func:`~bpb_tasks.billiards.stability_margins.pair_margins` on arrays, with the same
    float64 operations in the same order (same result to the bit).

    ``rows`` holds every segment as ``(ball, t0, t1, x, y, vx, vy, decel)``, balls numbered
    ``0..balls-1`` in id order and each ball's segments in time order; ``touched[a, b]`` marks
    pairs with a ball-ball event and ``moving[a]`` balls with a segment of non-zero velocity.
    Returns the near-miss gap and whether there is one, then the closest distance of the deepest
    overlap and whether it is under ``2 * radius - tolerance``.
    """
    pieces = np.empty((2 * rows.shape[0], 12))
    first = np.zeros(balls + 1, dtype=np.int64)
    count = 0
    for b in range(balls):
        first[b] = count
        for r in range(rows.shape[0]):
            if int(rows[r, 0]) == b:
                count = _add_pieces(pieces, count, rows[r])
    first[balls] = count
    best = 0.0
    found = False
    deepest = 2 * radius - tolerance
    overlapped = False
    for a in range(balls):
        for b in range(a + 1, balls):
            if not (moving[a] or moving[b]):
                continue
            a0, a1, b0, b1 = first[a], first[a + 1], first[b], first[b + 1]
            if touched[a, b]:
                closest = _closest(pieces, a0, a1, b0, b1, deepest)
            else:
                limit = best + 2 * radius if found else np.inf
                closest = _closest(pieces, a0, a1, b0, b1, limit)
                gap = closest - 2 * radius
                best = gap if not found or gap < best else best
                found = True
            if closest < deepest:
                deepest, overlapped = closest, True
    return best, found, deepest, overlapped


@jit
def _add_pieces(pieces: Arr, count: int, row: Arr) -> int:
    """Append a segment's pieces ``(t0, t1, x, y, vx, vy, ax, ay, box)`` (``_pieces`` and
    ``_box`` of the reference); returns the new count."""
    t0, t1, x, y, vx, vy, decel = row[1], row[2], row[3], row[4], row[5], row[6], row[7]
    speed = math.hypot(vx, vy)
    if speed == 0 or decel == 0:
        _piece(pieces, count, t0, t1, x, y, vx, vy, 0.0, 0.0)
        return count + 1
    ux, uy = vx / speed, vy / speed
    stop = t0 + speed / decel
    _piece(pieces, count, t0, t1 if t1 < stop else stop, x, y, vx, vy, -decel * ux, -decel * uy)
    if stop < t1:
        reach = speed * speed / (2 * decel)
        _piece(pieces, count + 1, stop, t1, x + ux * reach, y + uy * reach, 0.0, 0.0, 0.0, 0.0)
        return count + 2
    return count + 1


@jit
def _piece(
    pieces: Arr,
    k: int,
    t0: float,
    t1: float,
    x: float,
    y: float,
    vx: float,
    vy: float,
    ax: float,
    ay: float,
) -> None:
    p = pieces[k]
    p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7] = t0, t1, x, y, vx, vy, ax, ay
    x0, y0 = _at_x(p, t0), _at_y(p, t0)
    x1, y1 = _at_x(p, t1), _at_y(p, t1)
    p[8], p[9] = _min(x0, x1), _max(x0, x1)
    p[10], p[11] = _min(y0, y1), _max(y0, y1)


@jit
def _closest(pieces: Arr, a0: int, a1: int, b0: int, b1: int, limit: float) -> float:
    """``_closest_boxed`` of the reference over pieces ``a0:a1`` and ``b0:b1``."""
    best = limit
    for i in range(a0, a1):
        pa = pieces[i]
        for j in range(b0, b1):
            pb = pieces[j]
            lo, hi = _max(pa[0], pb[0]), _min(pa[1], pb[1])
            if lo > hi or _box_gap(pa, pb) >= best:
                continue
            best = _min(best, _pair_closest(pa, pb, lo, hi))
    return best


@jit
def _box_gap(a: Arr, b: Arr) -> float:
    dx = _max(_max(0.0, b[8] - a[9]), a[8] - b[9])
    dy = _max(_max(0.0, b[10] - a[11]), a[10] - b[11])
    return math.hypot(dx, dy) * (1 - 1e-12)


@jit
def _pair_closest(pa: Arr, pb: Arr, lo: float, hi: float) -> float:
    dx, dy = _at_x(pa, lo) - _at_x(pb, lo), _at_y(pa, lo) - _at_y(pb, lo)
    vx, vy = _at_vx(pa, lo) - _at_vx(pb, lo), _at_vy(pa, lo) - _at_vy(pb, lo)
    ax, ay = (pa[6] - pb[6]) / 2, (pa[7] - pb[7]) / 2
    c = (
        ax * ax + ay * ay,
        2 * (ax * vx + ay * vy),
        vx * vx + vy * vy + 2 * (ax * dx + ay * dy),
        2 * (vx * dx + vy * dy),
        dx * dx + dy * dy,
    )
    span = hi - lo
    best = _root_gap(c, 0.0)
    if span > 0:
        best = _min(best, _root_gap(c, span))
        p1, p2, p3, n = critical_points(c, span)
        if n > 0:
            best = _min(best, _root_gap(c, p1))
        if n > 1:
            best = _min(best, _root_gap(c, p2))
        if n > 2:
            best = _min(best, _root_gap(c, p3))
    return best


@jit
def _root_gap(c: Poly, t: float) -> float:
    return math.sqrt(_max(horner(c, t), 0.0))


@jit
def _at_x(p: Arr, t: float) -> float:
    tau = t - p[0]
    x: float = p[2] + p[4] * tau + p[6] * tau * tau / 2
    return x


@jit
def _at_y(p: Arr, t: float) -> float:
    tau = t - p[0]
    y: float = p[3] + p[5] * tau + p[7] * tau * tau / 2
    return y


@jit
def _at_vx(p: Arr, t: float) -> float:
    vx: float = p[4] + p[6] * (t - p[0])
    return vx


@jit
def _at_vy(p: Arr, t: float) -> float:
    vy: float = p[5] + p[7] * (t - p[0])
    return vy


@jit
def _min(a: float, b: float) -> float:
    """Python's ``min(a, b)``: ``a`` unless ``b`` is smaller."""
    return b if b < a else a


@jit
def _max(a: float, b: float) -> float:
    """Python's ``max(a, b)``: ``a`` unless ``b`` is larger."""
    return b if b > a else a
