"""Stability annotation: how close a scene's labels are to flipping (SPEC section 3).

Margins are read off the simulated outcome:

* ``near_miss_gap``: over pairs of balls that never touched (at least one of them moving at some
  time), the smallest gap ``distance - 2R`` over ``[0, horizon]``, found exactly per piece of
  motion (the squared distance is a quartic; its minimum is at an end or a critical point).
* ``min_graze_cos``: over ball-ball contacts, the smallest ``|cos|`` between the relative velocity
  and the line of centres (near 0 = grazing).
* ``min_event_gap``: the smallest time between two consecutive events of one ball (stops ignored).
* ``horizon_gap``: the time between the horizon and the nearest ball, wall or pocket event,
  looking up to one second past the horizon (an event just after it is as fragile as one before).

Flips: the scene is re-simulated under small perturbations of size ``delta`` and its labels (Q1
contacts, Q2 walls, pocketed balls) compared. The 12 perturbations are the cue position moved by
``+-delta`` in x and y, the cue direction turned by ``+-delta`` radians, the cue speed changed by
``+-delta`` m/s, and four moves of every object ball by ``+-delta`` per axis with signs drawn from
a generator seeded by the scene id. ``stable`` means no label flipped.
"""

from __future__ import annotations

import itertools
import math
import random
from collections.abc import Iterator

from bpb_core.interfaces import Simulator
from bpb_tasks.billiards.outcome import CUE_ID, Outcome, Segment
from bpb_tasks.billiards.scene import Scene
from bpb_tasks.billiards.truth import Stability
from bpb_tasks.simulators.analytic.numeric import FLOAT64
from bpb_tasks.simulators.analytic.roots import critical_points, horner

Labels = tuple[frozenset[int], frozenset[str], frozenset[int]]


def annotate(
    scene: Scene,
    outcome: Outcome | None = None,
    *,
    delta: float = 1e-4,
    simulator: Simulator | None = None,
) -> Stability:
    """Margins and label flips of ``scene`` (simulated with ``simulator``, default analytic)."""
    if simulator is None:
        from bpb_tasks.simulators.analytic import AnalyticSimulator

        simulator = AnalyticSimulator()
    base = outcome if outcome is not None else simulator.run(scene)
    reference = labels(base)
    flips: set[str] = set()
    for variant in perturbations(scene, delta):
        flips.update(flipped(reference, labels(simulator.run(variant, base.horizon))))
    radius = scene.physics.ball_radius
    later = simulator.run(scene, base.horizon + 1.0)
    return Stability(
        stable=not flips,
        delta=delta,
        near_miss_gap=near_miss_gap(base, radius),
        min_graze_cos=min_graze_cos(base),
        min_event_gap=min_event_gap(base),
        horizon_gap=horizon_gap(later, base.horizon),
        flips=sorted(flips, key=_flip_order),
    )


def labels(outcome: Outcome) -> Labels:
    """Q1 contacts, Q2 walls and the pocketed balls of an outcome."""
    pocketed = frozenset(i for i, p in outcome.positions.items() if p is None)
    return frozenset(outcome.cue_contacts()), frozenset(outcome.cue_walls()), pocketed


def flipped(reference: Labels, other: Labels) -> Iterator[str]:
    """Names of the labels that differ, e.g. ``q1:3``, ``q2:TOP``, ``q3:pocket:5``."""
    for prefix, a, b in zip(("q1", "q2", "q3:pocket"), reference, other, strict=True):
        for item in a ^ b:
            yield f"{prefix}:{item}"


def _flip_order(name: str) -> tuple[str, str]:
    head, _, tail = name.rpartition(":")
    return head, tail.zfill(8)


def perturbations(scene: Scene, delta: float) -> Iterator[Scene]:
    """The 12 perturbed copies of ``scene`` (see the module docstring)."""
    cue = scene.ball(CUE_ID)
    x, y = cue.pos
    vx, vy = cue.vel
    speed = math.hypot(vx, vy)
    for dx, dy in ((delta, 0.0), (-delta, 0.0), (0.0, delta), (0.0, -delta)):
        yield _with_ball(scene, CUE_ID, (x + dx, y + dy), cue.vel)
    for turn in (delta, -delta):
        c, s = math.cos(turn), math.sin(turn)
        yield _with_ball(scene, CUE_ID, cue.pos, (vx * c - vy * s, vx * s + vy * c))
    for change in (delta, -delta):
        scale = max(speed + change, 0.0) / speed if speed > 0 else 0.0
        yield _with_ball(scene, CUE_ID, cue.pos, (vx * scale, vy * scale))
    rng = random.Random(f"stability:{scene.scene_id}")
    for _ in range(4):
        balls = [
            b
            if b.id == CUE_ID
            else b.model_copy(
                update={
                    "pos": (
                        b.pos[0] + rng.choice((-delta, delta)),
                        b.pos[1] + rng.choice((-delta, delta)),
                    )
                }
            )
            for b in scene.balls
        ]
        yield scene.model_copy(update={"balls": balls})


def _with_ball(
    scene: Scene, ball_id: int, pos: tuple[float, float], vel: tuple[float, float]
) -> Scene:
    balls = [
        b.model_copy(update={"pos": pos, "vel": vel}) if b.id == ball_id else b for b in scene.balls
    ]
    return scene.model_copy(update={"balls": balls})


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


def horizon_gap(outcome: Outcome, horizon: float) -> float | None:
    """Time between ``horizon`` and the nearest non-stop event of ``outcome``."""
    gaps = [abs(e.t - horizon) for e in outcome.events if e.kind != "stop"]
    return min(gaps) if gaps else None


def near_miss_gap(outcome: Outcome, radius: float) -> float | None:
    """Smallest gap over the trajectories of pairs that never touched (see module docstring)."""
    touched = {tuple(sorted(e.ids)) for e in outcome.events if e.kind == "ball"}
    best: float | None = None
    for a, b in itertools.combinations(sorted(outcome.segments), 2):
        if (a, b) in touched:
            continue
        sa, sb = outcome.segments[a], outcome.segments[b]
        if all(s.vel == (0.0, 0.0) for s in (*sa, *sb)):
            continue
        gap = _closest(sa, sb) - 2 * radius
        best = gap if best is None else min(best, gap)
    return best


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


def _closest(sa: tuple[Segment, ...], sb: tuple[Segment, ...]) -> float:
    best = math.inf
    for (a0, a1, pa), (b0, b1, pb) in itertools.product(_pieces(sa), _pieces(sb)):
        lo, hi = max(a0, b0), min(a1, b1)
        if lo > hi:
            continue
        d = [_at(pa, a0, lo)[k] - _at(pb, b0, lo)[k] for k in range(4)]
        ax, ay = (pa[4] - pb[4]) / 2, (pa[5] - pb[5]) / 2
        dx, dy, vx, vy = d
        coeffs = [
            ax * ax + ay * ay,
            2 * (ax * vx + ay * vy),
            vx * vx + vy * vy + 2 * (ax * dx + ay * dy),
        ]
        coeffs += [2 * (vx * dx + vy * dy), dx * dx + dy * dy]
        span = hi - lo
        candidates = [0.0, span, *critical_points(coeffs, span, FLOAT64)] if span > 0 else [0.0]
        best = min(best, min(math.sqrt(max(horner(coeffs, t), 0.0)) for t in candidates))
    return best


def _at(p: tuple[float, ...], t0: float, t: float) -> tuple[float, float, float, float]:
    tau = t - t0
    return (
        p[0] + p[2] * tau + p[4] * tau * tau / 2,
        p[1] + p[3] * tau + p[5] * tau * tau / 2,
        p[2] + p[4] * tau,
        p[3] + p[5] * tau,
    )
