"""The compiled parts of the stability annotation (called from
:mod:`bpb_tasks.billiards.stability_batch`).

* :func:`tally_copies` runs each perturbed copy through the kernel and folds its event rows and
  final state into the tally at once: label bit masks per copy (cue contacts, cue walls,
  pocketed balls; one bit per ball index or wall), XORed against the nominal masks, and the
  largest distance of a ball from its nominal final position. No per-copy table is built.
* :func:`horizon_event_gap` is the horizon gap of
  :mod:`bpb_tasks.billiards.stability_margins` read off a kernel run's event rows.
* :func:`pair_margin_arrays` is the near-miss margin and the overlap of
  :mod:`bpb_tasks.billiards.stability_margins` (the reference, ``pair_margins``) with the same
  float64 operations in the same order; :func:`margin_arrays` adds the pocket-edge passes
  (:func:`pocket_offsets`).
"""

from __future__ import annotations

import math

import numpy as np

from bpb_tasks.simulators.analytic.kernel import buffers, run_into, run_rows
from bpb_tasks.simulators.analytic.kernel_predict import BALL, STOP, WALL, Arr
from bpb_tasks.simulators.analytic.kernel_roots import Poly, critical_points, horner, jit


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
    work = buffers(n)  # one set of working arrays for every copy
    events, final = work[4], work[6]
    for c in range(copies):
        a, b = c * n, (c + 1) * n
        status = run_into(work, pos[a:b], vel[a:b], prm, pockets, horizon, max_events)
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
def horizon_event_gap(
    pos: Arr, vel: Arr, prm: Arr, pockets: Arr, horizon: float, end: float, max_events: int
) -> tuple[float, bool, int, float]:
    """The smallest ``|t - horizon|`` over the ball, wall and pocket events (not stops) of the
    balls ``pos``/``vel`` run to ``end``, whether there is such an event, the run's status
    (1: stopped after ``max_events`` events, the events so far counted) and the time of the
    last event processed (-inf without one)."""
    events, _, _, status = run_rows(pos, vel, prm, pockets, end, max_events)
    best = np.inf
    found = False
    last = -np.inf
    for row in events:
        last = row[0]
        if row[1] != STOP:
            gap = abs(row[0] - horizon)
            best = gap if not found or gap < best else best
            found = True
    return best, found, status, last


@jit
def pair_margin_arrays(
    rows: Arr, balls: int, touched: Arr, moving: Arr, radius: float, tolerance: float
) -> tuple[float, bool, float, bool]:
    """:func:`~bpb_tasks.billiards.stability_margins.pair_margins` on arrays, with the same
    float64 operations in the same order (same result to the bit).

    ``rows`` holds every segment as ``(ball, t0, t1, x, y, vx, vy, decel, ...)``, balls numbered
    ``0..balls-1`` in id order and each ball's segments in time order; ``touched[a, b]`` marks
    pairs with a ball-ball event and ``moving[a]`` balls with a segment of non-zero velocity.
    Returns the near-miss gap and whether there is one, then the closest distance of the deepest
    overlap and whether it is under ``2 * radius - tolerance``.
    """
    pieces, first = _ball_pieces(rows, balls, False)
    return _pair_margins(pieces, first, touched, moving, radius, tolerance)


@jit
def margin_arrays(
    rows: Arr,
    balls: int,
    touched: Arr,
    moving: Arr,
    radius: float,
    tolerance: float,
    pocketed: Arr,
    centers: Arr,
) -> tuple[float, bool, float, bool, Arr, Arr]:
    """:func:`pair_margin_arrays` and :func:`pocket_offsets` (``pocketed[a]``: ball ``a`` ends
    in a pocket; ``centers``: the pockets) in one call. The pocket passes take each segment's
    speed from column 8 of ``rows`` (Python's hypot, as the reference ``pocket_gap``); the
    pair margins keep numba's, as :func:`pair_margin_arrays` always has."""
    pieces, first = _ball_pieces(rows, balls, False)
    best, found, deepest, overlapped = _pair_margins(
        pieces, first, touched, moving, radius, tolerance
    )
    pieces, first = _ball_pieces(rows, balls, True)
    passes, entering = pocket_offsets(pieces, first, pocketed, centers)
    return best, found, deepest, overlapped, passes, entering


@jit
def pocket_offsets(pieces: Arr, first: Arr, pocketed: Arr, centers: Arr) -> tuple[Arr, Arr]:
    """``pocket_gap`` of :mod:`bpb_tasks.billiards.stability_margins` up to its ``math.hypot``
    (which numba does not reproduce to the bit): per moving piece and pocket, the offset
    ``(ex, ey)`` of the pocket centre from the nearest point of the piece's path. ``passes``
    holds them for every piece but the last of a pocketed ball; ``entering`` holds a row
    ``(x1, y1, ex_0, ey_0, ex_1, ...)`` for each of those, ``x1, y1`` its end (the reference
    leaves out the pocket nearest to it)."""
    balls, m = first.shape[0] - 1, centers.shape[0]
    passes = np.empty((first[balls] * m, 2))
    entering = np.empty((balls, 2 + 2 * m))
    count = ends = 0
    for b in range(balls):
        for j in range(first[b], first[b + 1]):
            p = pieces[j]
            if p[4] == 0 and p[5] == 0:
                continue
            x0, y0, x1, y1 = _at_x(p, p[0]), _at_y(p, p[0]), _at_x(p, p[1]), _at_y(p, p[1])
            last = pocketed[b] and j == first[b + 1] - 1
            if last:
                entering[ends, 0], entering[ends, 1] = x1, y1
            for k in range(m):
                ex, ey = _offset(centers[k, 0] - x0, centers[k, 1] - y0, x1 - x0, y1 - y0)
                if last:
                    entering[ends, 2 + 2 * k], entering[ends, 3 + 2 * k] = ex, ey
                else:
                    passes[count, 0], passes[count, 1] = ex, ey
                    count += 1
            ends += last
    return passes[:count], entering[:ends]


@jit
def _offset(px: float, py: float, dx: float, dy: float) -> tuple[float, float]:
    """``_segment_distance`` of the reference before its hypot."""
    length2 = dx * dx + dy * dy
    k = 0.0 if length2 == 0 else _min(_max((px * dx + py * dy) / length2, 0.0), 1.0)
    return px - k * dx, py - k * dy


@jit
def _ball_pieces(rows: Arr, balls: int, given_speeds: bool) -> tuple[Arr, Arr]:
    """The pieces of every ball's segments (``_add_pieces``), ball ``b``'s at
    ``first[b]:first[b + 1]``; a segment's speed is its row's column 8 when ``given_speeds``
    (Python's ``math.hypot``, which numba's differs from in the last bit now and then), else
    numba's hypot of its velocity."""
    pieces = np.empty((2 * rows.shape[0], 12))
    first = np.zeros(balls + 1, dtype=np.int64)
    count = 0
    for b in range(balls):
        first[b] = count
        for r in range(rows.shape[0]):
            if int(rows[r, 0]) == b:
                row = rows[r]
                speed = row[8] if given_speeds else math.hypot(row[5], row[6])
                count = _add_pieces(pieces, count, row, speed)
    first[balls] = count
    return pieces, first


@jit
def _pair_margins(
    pieces: Arr, first: Arr, touched: Arr, moving: Arr, radius: float, tolerance: float
) -> tuple[float, bool, float, bool]:
    balls = first.shape[0] - 1
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
def _add_pieces(pieces: Arr, count: int, row: Arr, speed: float) -> int:
    """Append a segment's pieces ``(t0, t1, x, y, vx, vy, ax, ay, box)`` (``_pieces`` and
    ``_box`` of the reference) given its ``speed``; returns the new count."""
    t0, t1, x, y, vx, vy, decel = row[1], row[2], row[3], row[4], row[5], row[6], row[7]
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
