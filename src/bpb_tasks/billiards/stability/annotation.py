"""Stability annotation: how likely a scene's labels are to flip (SPEC section 3).

The scene is re-simulated under ``samples`` (default 64) random perturbations of size ``delta``
(default 1e-4): every ball's centre moves by ``delta`` metres in a uniformly random direction, and
the cue ball's velocity gains a vector of length ``delta`` times its speed in a uniformly random
direction. The draws come from a generator seeded by the scene id, so the annotation is
deterministic. For each perturbation the labels are compared with the nominal ones:

* flip rates (share of perturbations that flip at least one label) for Q1 (cue contacts), Q2
  (cue walls) and pocketed balls, and their union with its exact (Clopper-Pearson) upper 95%
  bound;
* the Q3 spread: the largest distance between a ball's perturbed and nominal final positions,
  over balls on the table in both and over perturbations. Q3 counts as unstable when the spread
  exceeds half a ball radius.

``stable`` means no label flipped in any perturbation, the Q3 spread is within the bound and no
two balls overlap in the nominal run (a pressing contact, which the event model does not
resolve; the analytic engine only). The deterministic margins
(:mod:`bpb_tasks.billiards.stability.margins`) are recorded alongside; ``stable`` does not depend
on them (a ``horizon_gap`` left unmeasured at the event cap, or where pymunk's run past the
horizon stopped, included).
Perturbed copies skip scene validation (a copy may touch a wall or another ball); with the
analytic engine's compiled kernel they run as one batch there
(:mod:`bpb_tasks.billiards.stability.kernel`). Either way every written number comes from the
same Python functions, so the annotation does not depend on whether numba is installed.
"""

from __future__ import annotations

import functools
import hashlib
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field

import numpy as np

from bpb_core.interfaces import Simulator
from bpb_tasks.billiards.scene.model import Ball, Scene
from bpb_tasks.billiards.stability.margins import (
    capped_horizon_gap,
    events_horizon_gap,
    min_event_gap,
    min_graze_cos,
    pair_margins,
    pocket_gap,
    times_horizon_gap,
)
from bpb_tasks.billiards.truth.final import UNFINISHED, Stability
from bpb_tasks.billiards.truth.outcome import CUE_ID, Outcome
from bpb_tasks.simulators.analytic.engine import AnalyticSimulator, SimulationError
from bpb_tasks.simulators.pymunk_sim import PymunkSimulator

Labels = tuple[frozenset[int], frozenset[str], frozenset[int]]
Positions = dict[int, tuple[float, float] | None]
DEFAULT_SAMPLES = 64
COPY_MIN_EVENTS = 1_000
COPY_EVENT_FACTOR = 10
GROUPS = ("q1", "q2", "pocketed")
KERNEL_MAX_BALLS = 63  # the kernel's label masks hold one bit per ball in an int64


@dataclass
class Tally:
    """Flip counts per label group, copies with any flip, flipped label names, Q3 spread, and
    copies left unfinished at the event budget (counted among the copies with any flip and
    named :data:`UNFINISHED` in ``flips``)."""

    counts: dict[str, int]
    any_flip: int = 0
    flips: set[str] = field(default_factory=set)
    spread: float = 0.0
    unfinished: int = 0


def annotate(
    scene: Scene,
    outcome: Outcome | None = None,
    *,
    delta: float = 1e-4,
    samples: int = DEFAULT_SAMPLES,
    simulator: Simulator | None = None,
) -> Stability:
    """Flip rates, Q3 spread and margins of ``scene`` (simulated with ``simulator``, default
    analytic). The overlap is the analytic engine's only: a simulator that steps time (pymunk)
    lets touching balls sink into each other by design (up to about 1 mm at its default
    step), so there it is ``None``, not a finding."""
    if simulator is None:
        simulator = AnalyticSimulator()
    base = outcome if outcome is not None else simulator.run(scene)
    ids, pos, vel = perturbation_arrays(scene, delta, samples)
    copies, finals = _copies(scene, base, ids, pos, vel, simulator)
    tally = tally_copies(labels(base), copies, finals, _positions(base.positions, ids))
    counts, any_flip, spread = tally.counts, tally.any_flip, tally.spread
    radius, pockets = scene.physics.ball_radius, scene.pockets
    gap, overlap = pair_margins(base, radius)
    return Stability(
        stable=any_flip == 0 and spread <= radius / 2 and overlap is None,
        delta=delta,
        samples=samples,
        flip_rates={g: counts[g] / samples for g in GROUPS},
        flip_rate=any_flip / samples,
        flip_rate_upper95=upper_bound(any_flip, samples),
        q3_spread=spread,
        q3_stable=spread <= radius / 2,
        near_miss_gap=gap,
        min_graze_cos=min_graze_cos(base),
        min_event_gap=min_event_gap(base),
        horizon_gap=_horizon_gap(scene, base.horizon, simulator),
        pocket_gap=pocket_gap(base, pockets.centers, pockets.radius),
        overlap=overlap if isinstance(simulator, AnalyticSimulator) else None,
        flips=sorted(tally.flips, key=_flip_order),
    )


def copy_budget(nominal_events: int, max_events: int) -> int:
    """The event budget of a perturbed copy: :data:`COPY_EVENT_FACTOR` times the nominal run's
    events, at least :data:`COPY_MIN_EVENTS`, at most the simulator's own ``max_events``."""
    return min(max_events, max(COPY_MIN_EVENTS, COPY_EVENT_FACTOR * nominal_events))


def _copies(
    scene: Scene,
    base: Outcome,
    ids: list[int],
    pos: np.ndarray,
    vel: np.ndarray,
    simulator: Simulator,
) -> tuple[list[Labels | None], np.ndarray]:
    """Each copy's labels (``None``: the analytic engine did not finish it within
    :func:`copy_budget` events) and ``(k, n, 2)`` final positions (NaN where pocketed or
    unfinished): in one compiled call when ``simulator`` takes the kernel for them and the
    scene has at most :data:`KERNEL_MAX_BALLS` balls, else copy by copy."""
    if isinstance(simulator, AnalyticSimulator):
        budget = copy_budget(len(base.events), simulator.max_events)
        events = len(base.events)
        if len(ids) <= KERNEL_MAX_BALLS and simulator.takes_kernel(scene, len(pos), events):
            from bpb_tasks.billiards.stability.kernel import copy_labels

            return copy_labels(scene, ids, pos, vel, budget)
        simulator = simulator.with_max_events(budget)
    copies: list[Labels | None] = []
    finals = np.full(pos.shape, np.nan)
    for k in range(len(pos)):
        copy = unvalidated_copy(scene, ids, pos[k].tolist(), vel[k].tolist())
        try:
            out = simulator.run(copy, base.horizon)
        except SimulationError:
            copies.append(None)
            continue
        copies.append(labels(out))
        finals[k] = _positions(out.positions, ids)
    return copies, finals


def _positions(positions: Positions, ids: list[int]) -> np.ndarray:
    """The ``(n, 2)`` positions of balls ``ids`` (NaN for a pocketed one)."""
    return np.array([positions[i] or (math.nan, math.nan) for i in ids], dtype=float)


def tally_copies(
    reference: Labels, copies: Sequence[Labels | None], finals: np.ndarray, nominal: np.ndarray
) -> Tally:
    """The tally of the copies' labels against ``reference`` and their final positions
    against ``nominal`` (see :func:`q3_spread`); a copy without labels counts unfinished."""
    tally = Tally(counts=dict.fromkeys(GROUPS, 0))
    for other in copies:
        if other is None:
            tally.unfinished += 1
            tally.any_flip += 1
            tally.flips.add(UNFINISHED)
            continue
        if other == reference:  # most copies: nothing flipped, nothing to count
            continue
        names = list(flipped(reference, other))
        tally.flips.update(names)
        tally.any_flip += bool(names)
        for group, a, b in zip(GROUPS, reference, other, strict=True):
            tally.counts[group] += a != b
    tally.spread = q3_spread(nominal, finals)
    return tally


def q3_spread(nominal: np.ndarray, finals: np.ndarray) -> float:
    """Largest distance between a ball's nominal final position (``(n, 2)``) and its final
    positions in the copies (``(k, n, 2)``), over balls on the table in both (NaN where not)."""
    gaps = np.hypot(finals[..., 0] - nominal[:, 0], finals[..., 1] - nominal[:, 1])
    gaps = gaps[~np.isnan(gaps)]
    return float(gaps.max()) if gaps.size else 0.0


def _horizon_gap(scene: Scene, horizon: float, simulator: Simulator) -> float | None:
    """:func:`horizon_gap` of a run to ``horizon`` + 1 s: from the kernel's event rows when
    it is loaded, else from the analytic engine's events or another simulator's outcome. The
    analytic engine's run stops at its event cap instead of failing the scene, which ran to
    its horizon within it: the gap is then measured on the events up to the cap
    (:func:`~bpb_tasks.billiards.stability.margins.capped_horizon_gap`; ``None`` when they
    do not decide it), on both paths alike. pymunk's run stops, by the same rule, where it
    would fail: a ball through a cushion, its step budget."""
    if isinstance(simulator, AnalyticSimulator) and simulator.kernel_loaded():
        return kernel_horizon_gap(scene, horizon, simulator.max_events)
    if isinstance(simulator, AnalyticSimulator):
        events, finished = simulator.capped_events(scene, horizon + 1.0)
        return events_horizon_gap(events, horizon, finished=finished)
    if isinstance(simulator, PymunkSimulator):
        events, stopped = simulator.events_until_failure(scene, horizon + 1.0)
        gap = events_horizon_gap(events, horizon)
        return gap if stopped is None else capped_horizon_gap(gap, stopped, horizon)
    return events_horizon_gap(simulator.run(scene, horizon + 1.0).events, horizon)


def kernel_horizon_gap(scene: Scene, horizon: float, max_events: int) -> float | None:
    """The analytic engine's horizon gap of ``scene`` (a run to ``horizon`` + 1 s stopping
    after ``max_events`` events) from the kernel's event rows."""
    from bpb_tasks.simulators.analytic.kernel import STOP, run_batch

    _, _, _, status, events = run_batch([scene], [horizon + 1.0], max_events, check=False)
    rows = events[:, 1:3].tolist()
    times = [t for t, kind in rows if kind != STOP]
    return times_horizon_gap(times, rows[-1][0] if rows else None, horizon, not status[0])


def labels(outcome: Outcome) -> Labels:
    """Q1 contacts, Q2 walls and the pocketed balls of an outcome."""
    pocketed = frozenset(i for i, p in outcome.positions.items() if p is None)
    return frozenset(outcome.cue_contacts()), frozenset(outcome.cue_walls()), pocketed


def flipped(reference: Labels, other: Labels) -> Iterator[str]:
    """Names of the labels that differ, e.g. ``q1:3``, ``q2:TOP``, ``q3:pocket:5``."""
    for prefix, a, b in zip(("q1", "q2", "q3:pocket"), reference, other, strict=True):
        for item in a ^ b:
            yield f"{prefix}:{item}"


@functools.lru_cache(maxsize=256)
def upper_bound(flips: int, samples: int, level: float = 0.95) -> float:
    """Exact one-sided upper ``level`` bound on a rate with ``flips`` of ``samples`` observed
    (Clopper-Pearson; ``1 - 0.05 ** (1 / n)`` when nothing flipped)."""
    if flips >= samples:
        return 1.0
    alpha = 1 - level

    def cdf(p: float) -> float:
        return sum(
            math.comb(samples, k) * p**k * (1 - p) ** (samples - k) for k in range(flips + 1)
        )

    lo, hi = flips / samples, 1.0
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if cdf(mid) > alpha else (lo, mid)
    return hi


def _flip_order(name: str) -> tuple[str, str]:
    head, _, tail = name.rpartition(":")
    return head, tail.zfill(8)


def perturbation_arrays(
    scene: Scene, delta: float, samples: int, stream: str = "stability"
) -> tuple[list[int], np.ndarray, np.ndarray]:
    """Ball ids (sorted) and the ``(samples, n, 2)`` positions and velocities of the perturbed
    copies, drawn from a numpy generator seeded by ``stream`` and the scene id: per copy
    ``n + 1`` uniform angles, ball ``j`` moved by ``delta`` at angle ``j``, the cue ball's
    velocity kicked by ``delta`` times its speed at the last one."""
    balls = sorted(scene.balls, key=lambda b: b.id)
    ids = [b.id for b in balls]
    cue = ids.index(CUE_ID) if CUE_ID in ids else -1
    kick = delta * math.hypot(*balls[cue].vel) if cue >= 0 else 0.0
    centres = np.array([b.pos for b in balls], dtype=float).reshape(-1, 2)
    velocities = np.array([b.vel for b in balls], dtype=float).reshape(-1, 2)
    seed = hashlib.sha256(f"{stream}:{scene.scene_id}".encode()).digest()
    rng = np.random.default_rng(int.from_bytes(seed[:16], "little"))
    angles = rng.random((samples, len(balls) + 1)) * (2 * math.pi)
    pos = centres[None] + delta * np.stack(
        (np.cos(angles[:, :-1]), np.sin(angles[:, :-1])), axis=-1
    )
    vel = np.repeat(velocities[None], samples, axis=0)
    if cue >= 0:
        vel[:, cue, 0] += kick * np.cos(angles[:, -1])
        vel[:, cue, 1] += kick * np.sin(angles[:, -1])
    return ids, pos, vel


def unvalidated_copy(
    scene: Scene,
    ids: Sequence[int],
    pos: Sequence[Sequence[float]],
    vel: Sequence[Sequence[float]],
) -> Scene:
    """``scene`` with other ball states, built without validation."""
    balls = [
        Ball.model_construct(id=i, pos=(p[0], p[1]), vel=(v[0], v[1]))
        for i, p, v in zip(ids, pos, vel, strict=True)
    ]
    return scene.model_copy(update={"balls": balls})
