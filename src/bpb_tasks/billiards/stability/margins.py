"""Deterministic stability margins of a simulated outcome (SPEC section 3).

* ``near_miss_gap``: over pairs of balls that never touched (at least one of them moving at some
  time), the smallest gap ``distance - 2R`` over ``[0, horizon]``, found exactly per piece of
  motion (the squared distance is a quartic; its minimum is at an end or a critical point).
* ``min_graze_cos``: over ball-ball contacts, the smallest ``|cos|`` between the relative velocity
  and the line of centres (near 0 = grazing).
* ``min_event_gap``: the smallest time between two consecutive events of one ball (stops ignored).
* ``horizon_gap``: the time between the horizon and the nearest ball, wall or pocket event,
  looking up to one second past the horizon (an event just after it is as fragile as one before).
  The run past the horizon has the simulator's event cap (counted from ``t = 0``); one that
  reaches it stops there (:func:`capped_horizon_gap`) rather than fail a scene that ran to its
  horizon: the gap is still exact when an event after the horizon came before the cap (nearly
  always), and ``None`` (not measured) when no event up to the cap decides it. pymunk's run
  stops the same way where it would fail (a ball through a cushion, its step budget).
* ``pocket_gap``: the nearest pocket-edge pass: over moving balls and the pockets their centres
  pass without entering, the smallest ``closest distance - pocket radius``.
* ``overlap``: the deepest overlap of two balls, ``2R - closest distance`` over every pair (touched
  or not), when it exceeds the contact tolerance
  (:data:`~bpb_tasks.billiards.scene.model.TOUCH_TOLERANCE`); ``None`` otherwise. An event model
  keeps balls apart up to rounding (at most 2e-14 m over 3,000 generated scenes), except in a
  pressing contact, which it does not model (the dataset card's known limitation): there the ground
  truth shows two balls inside each other.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from bpb_tasks.billiards.scene.model import TOUCH_TOLERANCE
from bpb_tasks.billiards.truth.outcome import Event, Outcome, Segment
from bpb_tasks.simulators.analytic.engine import FLOAT64
from bpb_tasks.simulators.analytic.roots import critical_points, horner

Piece = tuple[float, float, tuple[float, ...]]
Box = tuple[float, float, float, float]


def pocket_gap(
    outcome: Outcome, centers: Sequence[tuple[float, float]], radius: float
) -> float | None:
    """Smallest positive ``distance - radius`` of a moving centre's path from a pocket centre it
    does not enter (see the module docstring); the last piece of a pocketed ball's path is not
    measured against the pocket it ends in."""
    best: float | None = None
    for ball, segments in outcome.segments.items():
        pieces = _pieces(segments)
        for j, (t0, t1, p) in enumerate(pieces):
            if p[2] == 0 and p[3] == 0:
                continue
            x0, y0, _, _ = _at(p, t0, t0)
            x1, y1, _, _ = _at(p, t0, t1)
            entered = -1
            if outcome.positions.get(ball, ()) is None and j == len(pieces) - 1:
                entered = min(range(len(centers)), key=lambda k: math.dist((x1, y1), centers[k]))
            for k, (cx, cy) in enumerate(centers):
                gap = _segment_distance(cx - x0, cy - y0, x1 - x0, y1 - y0) - radius
                if k != entered and gap > 0 and (best is None or gap < best):
                    best = gap
    return best


def _segment_distance(px: float, py: float, dx: float, dy: float) -> float:
    """Distance from ``(px, py)`` to the segment from the origin to ``(dx, dy)``."""
    length2 = dx * dx + dy * dy
    k = 0.0 if length2 == 0 else min(max((px * dx + py * dy) / length2, 0.0), 1.0)
    return math.hypot(px - k * dx, py - k * dy)


def min_graze_cos(outcome: Outcome) -> float | None:
    """Smallest ``|cos|`` of the approach angle over ball-ball contacts."""
    best: float | None = None
    for event in outcome.events:
        if event.kind != "ball":
            continue
        (ax, ay), (bx, by) = event.positions
        va, vb = (_velocity_before(outcome.segments[i], event.t) for i in event.ids)
        rx, ry = va[0] - vb[0], va[1] - vb[1]
        nx, ny = bx - ax, by - ay
        norm = math.hypot(rx, ry) * math.hypot(nx, ny)
        if norm > 0:
            value = abs(rx * nx + ry * ny) / norm
            best = value if best is None else min(best, value)
    return best


def _velocity_before(segments: tuple[Segment, ...], t: float) -> tuple[float, float]:
    earlier = [s for s in segments if s.t0 < t] or [segments[0]]
    seg = earlier[-1]
    speed = math.hypot(*seg.vel)
    if speed == 0:
        return 0.0, 0.0
    left = max(speed - seg.decel * (t - seg.t0), 0.0) / speed
    return seg.vel[0] * left, seg.vel[1] * left


def min_event_gap(outcome: Outcome) -> float | None:
    """Smallest time between consecutive (non-stop) events sharing a ball."""
    times: dict[int, list[float]] = {}
    for event in outcome.events:
        if event.kind != "stop":
            for i in event.ids:
                times.setdefault(i, []).append(event.t)
    gaps = [b - a for ts in times.values() for a, b in itertools.pairwise(ts)]
    return min(gaps) if gaps else None


def events_horizon_gap(
    events: Sequence[Event], horizon: float, *, finished: bool = True
) -> float | None:
    """Time between ``horizon`` and the nearest non-stop event of ``events`` (in time order);
    ``finished=False``: of a run stopped at its event cap after them (see
    :func:`capped_horizon_gap`)."""
    times = [e.t for e in events if e.kind != "stop"]
    return times_horizon_gap(times, events[-1].t if events else None, horizon, finished)


def times_horizon_gap(
    times: Sequence[float], last: float | None, horizon: float, finished: bool
) -> float | None:
    """:func:`events_horizon_gap` from the times of the non-stop events and the time of the
    last event of all (``None`` without one)."""
    gaps = [abs(t - horizon) for t in times]
    best = min(gaps) if gaps else None
    if finished:
        return best
    return capped_horizon_gap(best, last, horizon) if last is not None else None


def capped_horizon_gap(best: float | None, last: float, horizon: float) -> float | None:
    """The horizon gap of a run stopped early, at its event cap or where pymunk's run would
    fail: ``best``, the gap over the events it processed, when no later event can be nearer
    (each is at or after ``last``, the time of the last one processed or of pymunk's last
    step; so always when a non-stop event after the horizon was processed), else ``None``:
    not measured."""
    return best if best is not None and best <= last - horizon else None


def pair_margins(outcome: Outcome, radius: float) -> tuple[float | None, float | None]:
    """``(near_miss_gap, overlap)`` in one pass over the pairs (see the module docstring).

    A touched pair is only measured closer than the deepest overlap so far (at first
    ``2R - TOUCH_TOLERANCE``): its contacts put it at ``2R`` anyway."""
    touched = {tuple(sorted(e.ids)) for e in outcome.events if e.kind == "ball"}
    boxed: dict[int, list[tuple[Piece, Box]]] = {}
    best: float | None = None
    deepest = 2 * radius - TOUCH_TOLERANCE  # a closest distance under this is an overlap
    overlapped = False
    for a, b in itertools.combinations(sorted(outcome.segments), 2):
        sa, sb = outcome.segments[a], outcome.segments[b]
        if all(s.vel == (0.0, 0.0) for s in (*sa, *sb)):
            continue
        for ball, segments in ((a, sa), (b, sb)):
            if ball not in boxed:
                boxed[ball] = [(piece, _box(piece)) for piece in _pieces(segments)]
        if (a, b) in touched:
            closest = _closest_boxed(boxed[a], boxed[b], deepest)
        else:
            limit = math.inf if best is None else best + 2 * radius
            closest = _closest_boxed(boxed[a], boxed[b], limit)
            gap = closest - 2 * radius
            best = gap if best is None else min(best, gap)
        if closest < deepest:
            deepest, overlapped = closest, True
    return best, (2 * radius - deepest if overlapped else None)


def _pieces(segments: tuple[Segment, ...]) -> list[tuple[float, float, tuple[float, ...]]]:
    """Motion as ``(t0, t1, (x, y, vx, vy, ax, ay))`` pieces, split where a ball stops."""
    out: list[tuple[float, float, tuple[float, ...]]] = []
    for s in segments:
        speed = math.hypot(*s.vel)
        if speed == 0 or s.decel == 0:
            ax = ay = 0.0
            out.append((s.t0, s.t1, (*s.pos, *s.vel, ax, ay)))
            continue
        ux, uy = s.vel[0] / speed, s.vel[1] / speed
        stop = s.t0 + speed / s.decel
        out.append((s.t0, min(stop, s.t1), (*s.pos, *s.vel, -s.decel * ux, -s.decel * uy)))
        if stop < s.t1:
            reach = speed * speed / (2 * s.decel)
            out.append(
                (stop, s.t1, (s.pos[0] + ux * reach, s.pos[1] + uy * reach, 0.0, 0.0, 0.0, 0.0))
            )
    return out


def _closest_boxed(
    boxes_a: list[tuple[Piece, Box]], boxes_b: list[tuple[Piece, Box]], limit: float
) -> float:
    """Closest approach of two balls' centres (their pieces with bounding boxes), or at least
    ``limit`` when it is no closer (piece pairs whose boxes are ``limit`` or more apart are
    skipped)."""
    best = limit
    for (a0, a1, pa), box_a in boxes_a:
        for (b0, b1, pb), box_b in boxes_b:
            lo, hi = max(a0, b0), min(a1, b1)
            if lo > hi or _box_gap(box_a, box_b) >= best:
                continue
            best = min(best, _pair_closest(a0, pa, b0, pb, lo, hi))
    return best


def _box(piece: Piece) -> Box:
    """Bounding box of a piece's path (a straight stretch: its two ends)."""
    t0, t1, p = piece
    x0, y0, _, _ = _at(p, t0, t0)
    x1, y1, _, _ = _at(p, t0, t1)
    return min(x0, x1), max(x0, x1), min(y0, y1), max(y0, y1)


def _box_gap(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    dx = max(0.0, b[0] - a[1], a[0] - b[1])
    dy = max(0.0, b[2] - a[3], a[2] - b[3])
    return math.hypot(dx, dy) * (1 - 1e-12)  # never skip a pair at the exact bound


def _pair_closest(
    a0: float, pa: tuple[float, ...], b0: float, pb: tuple[float, ...], lo: float, hi: float
) -> float:
    """Closest approach of two pieces over their common time ``[lo, hi]``."""
    at_a, at_b = _at(pa, a0, lo), _at(pb, b0, lo)
    dx, dy, vx, vy = (at_a[k] - at_b[k] for k in range(4))
    ax, ay = (pa[4] - pb[4]) / 2, (pa[5] - pb[5]) / 2
    coeffs = (
        ax * ax + ay * ay,
        2 * (ax * vx + ay * vy),
        vx * vx + vy * vy + 2 * (ax * dx + ay * dy),
        2 * (vx * dx + vy * dy),
        dx * dx + dy * dy,
    )
    span = hi - lo
    candidates = [0.0]
    if span > 0:
        *points, n = critical_points(coeffs, span, FLOAT64.time_tol, FLOAT64.max_iter)
        candidates += [span, *points[:n]]
    return min(math.sqrt(max(horner(coeffs, t), 0.0)) for t in candidates)


def _at(p: tuple[float, ...], t0: float, t: float) -> tuple[float, float, float, float]:
    tau = t - t0
    return (
        p[0] + p[2] * tau + p[4] * tau * tau / 2,
        p[1] + p[3] * tau + p[5] * tau * tau / 2,
        p[2] + p[4] * tau,
        p[3] + p[5] * tau,
    )
