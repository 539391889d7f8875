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
(:mod:`bpb_tasks.billiards.stability_margins`) are recorded alongside; ``stable`` does not depend
on them (a ``horizon_gap`` left unmeasured at the event cap, or where pymunk's run past the
horizon stopped, included).
Perturbed copies skip scene validation (a copy may touch a wall or another ball); with numba
installed they run as one batch in the compiled kernel.
"""

from __future__ import annotations

import functools
import importlib
import itertools
import math
import random
from collections.abc import Iterator, Sequence
from typing import TypeGuard

import numpy as np

from bpb_core.interfaces import Simulator
from bpb_tasks.billiards.outcome import CUE_ID, Outcome
from bpb_tasks.billiards.scene import Ball, Scene
from bpb_tasks.billiards.stability_batch import (
    KERNEL_MAX_BALLS,
    Tally,
    kernel_horizon_gap,
    kernel_margins,
    kernel_tally,
)
from bpb_tasks.billiards.stability_margins import (
    capped_horizon_gap,
    events_horizon_gap,
    horizon_gap,
    min_event_gap,
    min_graze_cos,
    pair_margins,
    pocket_gap,
)
from bpb_tasks.billiards.truth import Stability
from bpb_tasks.simulators.analytic.engine import AnalyticSimulator, SimulationError
from bpb_tasks.simulators.pymunk_sim import PymunkSimulator

Labels = tuple[frozenset[int], frozenset[str], frozenset[int]]
Positions = dict[int, tuple[float, float] | None]
DEFAULT_SAMPLES = 64
COPY_MIN_EVENTS = 1_000
COPY_EVENT_FACTOR = 10
GROUPS = ("q1", "q2", "pocketed")


def annotate(
    scene: Scene,
    outcome: Outcome | None = None,
    *,
    delta: float = 1e-4,
    samples: int = DEFAULT_SAMPLES,
    simulator: Simulator | None = None,
) -> Stability:
    """Flip rates, Q3 spread and margins of ``scene`` (simulated with ``simulator``, default
    analytic)."""
    if simulator is None:
        simulator = AnalyticSimulator()
    base = outcome if outcome is not None else simulator.run(scene)
    tally = _tally(scene, base, delta, samples, simulator)
    counts, any_flip, flips, spread = tally.counts, tally.any_flip, tally.flips, tally.spread
    radius = scene.physics.ball_radius
    gap, overlap, pocket = _margins(scene, base, simulator)
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
        pocket_gap=pocket,
        overlap=overlap,
        flips=sorted(flips, key=_flip_order),
    )


def copy_budget(nominal_events: int, max_events: int) -> int:
    """The event budget of a perturbed copy: :data:`COPY_EVENT_FACTOR` times the nominal run's
    events, at least :data:`COPY_MIN_EVENTS`, at most the simulator's own ``max_events``."""
    return min(max_events, max(COPY_MIN_EVENTS, COPY_EVENT_FACTOR * nominal_events))


def _tally(scene: Scene, base: Outcome, delta: float, samples: int, simulator: Simulator) -> Tally:
    """Flip counts and Q3 spread of the perturbed copies: on arrays in one compiled call when
    ``simulator`` runs the kernel and the scene has at most :data:`KERNEL_MAX_BALLS` balls,
    else copy by copy. A copy the analytic engine cannot finish within :func:`copy_budget`
    events is counted unfinished, not simulated further."""
    if _runs_kernel(simulator) and len(scene.balls) <= KERNEL_MAX_BALLS:
        ids, pos, vel = perturbation_arrays(scene, delta, samples, compiled=True)
        budget = copy_budget(len(base.events), simulator.max_events)
        return kernel_tally(scene, base, ids, pos, vel, budget)
    ids, pos, vel = perturbation_arrays(scene, delta, samples)
    reference = labels(base)
    tally = Tally(counts=dict.fromkeys(GROUPS, 0))
    runner = _budgeted(simulator, len(base.events))
    for k in range(samples):
        copy = unvalidated_copy(scene, ids, pos[k].tolist(), vel[k].tolist())
        try:
            out = runner.run(copy, base.horizon)
        except SimulationError:
            tally.add_unfinished()
            continue
        other = labels(out)
        names = list(flipped(reference, other))
        tally.flips.update(names)
        tally.any_flip += bool(names)
        for group, a, b in zip(GROUPS, reference, other, strict=True):
            tally.counts[group] += a != b
        tally.spread = max(tally.spread, q3_spread(base.positions, out.positions))
    return tally


def _budgeted(simulator: Simulator, nominal_events: int) -> Simulator:
    """``simulator`` with the copies' event budget (the analytic engine; others as they are)."""
    if isinstance(simulator, AnalyticSimulator):
        return simulator.with_max_events(copy_budget(nominal_events, simulator.max_events))
    return simulator


def _margins(
    scene: Scene, base: Outcome, simulator: Simulator
) -> tuple[float | None, float | None, float | None]:
    """The near-miss gap and the overlap (:func:`pair_margins`) and the :func:`pocket_gap`, in
    compiled code when ``simulator`` runs the kernel. The overlap is the analytic engine's only:
    a simulator that steps time (pymunk) lets touching balls sink into each other by design (up
    to about 1 mm at its default step), so there it is ``None``, not a finding."""
    radius, pockets = scene.physics.ball_radius, scene.pockets
    if _runs_kernel(simulator):
        gap, overlap, pocket = kernel_margins(base, radius, pockets.centers, pockets.radius)
    else:
        gap, overlap = pair_margins(base, radius)
        pocket = pocket_gap(base, pockets.centers, pockets.radius)
    return gap, overlap if isinstance(simulator, AnalyticSimulator) else None, pocket


def load_kernel(simulator: Simulator) -> None:
    """Load the compiled kernel before a scene's own run when its annotation will run it
    (:func:`_runs_kernel`): ``auto`` single runs take the kernel only once numba is loaded, so
    each process ran its first scene in Python and compiled the kernel's single-scene entry on
    its second; a pool's workers each built it, which the parent's first scene never had."""
    if _runs_kernel(simulator):
        importlib.import_module("bpb_tasks.simulators.analytic.kernel")


def _runs_kernel(simulator: Simulator) -> TypeGuard[AnalyticSimulator]:
    """Whether ``simulator`` is the analytic engine with its compiled kernel."""
    return isinstance(simulator, AnalyticSimulator) and simulator.compiled


def _horizon_gap(scene: Scene, horizon: float, simulator: Simulator) -> float | None:
    """:func:`horizon_gap` of a run to ``horizon`` + 1 s: in one compiled call from the
    kernel's event rows (the same events; no outcome is built) when single runs take the
    kernel, else from the analytic engine's events or another simulator's outcome. The
    analytic engine's run stops at its event cap instead of failing the scene, which ran to
    its horizon within it: the gap is then measured on the events up to the cap
    (:func:`~bpb_tasks.billiards.stability_margins.capped_horizon_gap`; ``None`` when they
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
    return horizon_gap(simulator.run(scene, horizon + 1.0), horizon)


def labels(outcome: Outcome) -> Labels:
    """Q1 contacts, Q2 walls and the pocketed balls of an outcome."""
    return labels_of(outcome.cue_contacts(), outcome.cue_walls(), outcome.positions)


def labels_of(contacts: set[int], walls: set[str], positions: Positions) -> Labels:
    """The labels from cue contacts, cue walls and final positions."""
    pocketed = frozenset(i for i, p in positions.items() if p is None)
    return frozenset(contacts), frozenset(walls), pocketed


def flipped(reference: Labels, other: Labels) -> Iterator[str]:
    """Names of the labels that differ, e.g. ``q1:3``, ``q2:TOP``, ``q3:pocket:5``."""
    for prefix, a, b in zip(("q1", "q2", "q3:pocket"), reference, other, strict=True):
        for item in a ^ b:
            yield f"{prefix}:{item}"


def q3_spread(nominal: Positions, other: Positions) -> float:
    """Largest distance between final positions of balls on the table in both."""
    best = 0.0
    for ball, pos in nominal.items():
        moved = other.get(ball)
        if pos is not None and moved is not None:
            best = max(best, math.dist(pos, moved))
    return best


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
    scene: Scene, delta: float, samples: int, stream: str = "stability", *, compiled: bool = False
) -> tuple[list[int], np.ndarray, np.ndarray]:
    """Ball ids and the ``(samples, n, 2)`` positions and velocities of the perturbed copies
    (drawn from a generator seeded by ``stream`` and the scene id); ``compiled`` builds the
    arrays in one compiled call (:func:`~bpb_tasks.billiards.stability_draws.perturb`, the
    same values to the bit; a test compares) instead of a Python call per draw and numpy
    operations."""
    seed = f"{stream}:{scene.scene_id}"
    if compiled:
        from bpb_tasks.billiards.stability_draws import perturb, seed_key
        from bpb_tasks.simulators.analytic.compiled import scene_arrays

        ids, centres, velocities = scene_arrays(scene)  # the nominal run's, kept
        cue = ids.index(CUE_ID) if CUE_ID in ids else -1
        kick = delta * math.hypot(*scene.ball(CUE_ID).vel) if cue >= 0 else 0.0
        pos, vel = perturb(seed_key(seed), samples, centres, velocities, delta, cue, kick)
        return ids, pos, vel
    balls = sorted(scene.balls, key=lambda b: b.id)
    ids = [b.id for b in balls]
    cue = ids.index(CUE_ID) if CUE_ID in ids else -1
    kick = delta * math.hypot(*balls[cue].vel) if cue >= 0 else 0.0
    centres = np.array([b.pos for b in balls], dtype=float).reshape(-1, 2)
    velocities = np.array([b.vel for b in balls], dtype=float).reshape(-1, 2)
    rng = random.Random(seed)
    count = samples * (len(balls) + 1)
    draws = list(itertools.starmap(rng.random, itertools.repeat((), count)))  # row by row
    angles = np.array(draws, dtype=float).reshape(samples, len(balls) + 1)
    angles *= 2 * math.pi
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
