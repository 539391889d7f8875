"""The kernel's side of the stability annotation: Python wrappers around
:mod:`bpb_tasks.billiards.stability_compiled`.

:func:`kernel_tally` hands every perturbed copy to
:func:`~bpb_tasks.billiards.stability_compiled.tally_copies`, which runs them through the kernel
and keeps only bit masks per copy (cue contacts, cue walls, pocketed balls, one bit per ball index
or wall), so flips are XORs against the nominal masks; no per-copy Python objects or tables are
built. It gives the same tally as running each copy through
:meth:`~bpb_tasks.simulators.analytic.AnalyticSimulator.run` (a test compares).
:func:`kernel_horizon_gap` is
:func:`~bpb_tasks.billiards.stability_margins.horizon_gap` from the kernel's event rows and
:func:`kernel_pair_margins` gives the near-miss margin and the overlap to the bit (a test
compares), :func:`kernel_margins` those and the pocket-edge margin.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from bpb_tasks.billiards.outcome import CUE_ID, Outcome
from bpb_tasks.billiards.scene import TOUCH_TOLERANCE, WALLS, Scene
from bpb_tasks.billiards.stability_margins import capped_horizon_gap
from bpb_tasks.billiards.truth import UNFINISHED

KERNEL_MAX_BALLS = 63  # one bit per ball index in an int64 mask, the sign bit unused


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

    def add_unfinished(self, copies: int = 1) -> None:
        """Count ``copies`` the simulator could not finish within their event budget."""
        self.unfinished += copies
        self.any_flip += copies
        if copies:
            self.flips.add(UNFINISHED)


def kernel_tally(
    scene: Scene,
    base: Outcome,
    ids: list[int],
    pos: np.ndarray,
    vel: np.ndarray,
    max_events: int,
) -> Tally:
    """Tally the copies ``pos``/``vel`` (``(k, n, 2)``, balls in ``ids`` order) of ``scene``
    against its nominal outcome ``base``; a copy needing more than ``max_events`` events is
    counted unfinished."""
    from bpb_tasks.billiards.stability_compiled import tally_copies
    from bpb_tasks.simulators.analytic.compiled import table_params

    n = pos.shape[1]
    prm, pockets = table_params(scene)
    counts, unions, any_flip, spread, unfinished = tally_copies(
        np.ascontiguousarray(pos.reshape(-1, 2)),
        np.ascontiguousarray(vel.reshape(-1, 2)),
        n,
        prm,
        pockets,
        float(base.horizon),
        max_events,
        ids.index(CUE_ID) if CUE_ID in ids else -1,
        np.array(_nominal(base, ids), dtype=np.int64),
        np.array([base.positions[i] or (np.nan, np.nan) for i in ids], dtype=float),
    )
    tally = Tally(counts={}, any_flip=int(any_flip), spread=float(spread))
    tally.add_unfinished(int(unfinished))
    groups = zip(_groups(ids), counts.tolist(), unions.tolist(), strict=True)
    for (group, prefix, names), count, union in groups:  # Python ints: numpy scalars are slow
        tally.counts[group] = count
        if union:
            tally.flips.update(f"{prefix}:{names[j]}" for j in range(len(names)) if union >> j & 1)
    return tally


def _groups(ids: list[int]) -> list[tuple[str, str, list[object]]]:
    """Group name, flip-name prefix and the label item of each bit."""
    balls: list[object] = list(ids)
    return [("q1", "q1", balls), ("q2", "q2", list(WALLS)), ("pocketed", "q3:pocket", balls)]


def _nominal(base: Outcome, ids: list[int]) -> tuple[int, int, int]:
    index = {ball: j for j, ball in enumerate(ids)}
    contacts = sum(1 << index[i] for i in base.cue_contacts())
    walls = sum(1 << WALLS.index(w) for w in base.cue_walls())
    pocketed = sum(1 << index[i] for i, p in base.positions.items() if p is None)
    return contacts, walls, pocketed


def kernel_horizon_gap(scene: Scene, horizon: float, max_events: int) -> float | None:
    """:func:`~bpb_tasks.billiards.stability_margins.horizon_gap` of ``scene`` run to
    ``horizon`` + 1 s by the kernel, in one compiled call (the same value to the bit). A run
    past ``max_events`` events stops there, as
    :meth:`~bpb_tasks.simulators.analytic.AnalyticSimulator.capped_events` does:
    :func:`~bpb_tasks.billiards.stability_margins.capped_horizon_gap` of the events so far."""
    from bpb_tasks.billiards.stability_compiled import horizon_event_gap
    from bpb_tasks.simulators.analytic.compiled import scene_arrays, table_params

    _, pos, vel = scene_arrays(scene)
    prm, pockets = table_params(scene)
    end = float(horizon) + 1.0
    gap, found, status, last = horizon_event_gap(
        pos, vel, prm, pockets, float(horizon), end, max_events
    )
    best = float(gap) if found else None
    return capped_horizon_gap(best, float(last), float(horizon)) if status else best


def kernel_pair_margins(outcome: Outcome, radius: float) -> tuple[float | None, float | None]:
    """:func:`~bpb_tasks.billiards.stability_margins.pair_margins` (near-miss gap, overlap) in
    compiled code (the same values to the bit; a test compares)."""
    from bpb_tasks.billiards.stability_compiled import pair_margin_arrays

    ids, rows, touched, moving = _segment_arrays(outcome)
    gap, found, deepest, overlapped = pair_margin_arrays(
        rows, len(ids), touched, moving, radius, TOUCH_TOLERANCE
    )
    return (float(gap) if found else None), (2 * radius - float(deepest) if overlapped else None)


def kernel_margins(
    outcome: Outcome, radius: float, centers: Sequence[tuple[float, float]], pocket_radius: float
) -> tuple[float | None, float | None, float | None]:
    """:func:`kernel_pair_margins` and
    :func:`~bpb_tasks.billiards.stability_margins.pocket_gap` in one compiled call (the same
    values to the bit; a test compares): only the final ``math.hypot`` of each pocket pass runs
    in Python, as numba's differs from it in the last bit now and then."""
    from bpb_tasks.billiards.stability_compiled import margin_arrays

    ids, rows, touched, moving = _segment_arrays(outcome)
    pocketed = np.array([outcome.positions.get(i, ()) is None for i in ids], dtype=np.bool_)
    gap, found, deepest, overlapped, passes, entering = margin_arrays(
        rows,
        len(ids),
        touched,
        moving,
        radius,
        TOUCH_TOLERANCE,
        pocketed,
        np.array(centers, dtype=float).reshape(-1, 2),
    )
    ex, ey = passes.T.tolist()
    gaps = [h - pocket_radius for h in map(math.hypot, ex, ey)]
    for x1, y1, *offsets in entering.tolist():
        entered = min(range(len(centers)), key=lambda k: math.dist((x1, y1), centers[k]))
        gaps.extend(
            math.hypot(offsets[2 * k], offsets[2 * k + 1]) - pocket_radius
            for k in range(len(centers))
            if k != entered
        )
    return (
        float(gap) if found else None,
        2 * radius - float(deepest) if overlapped else None,
        min((g for g in gaps if g > 0), default=None),
    )


def _segment_arrays(outcome: Outcome) -> tuple[list[int], np.ndarray, np.ndarray, np.ndarray]:
    """Ball ids (sorted), segment rows, touched pairs and moving balls of ``outcome`` as
    :func:`~bpb_tasks.billiards.stability_compiled.margin_arrays` takes them (each row ending
    in the segment's speed by Python's ``math.hypot``)."""
    ids = sorted(outcome.segments)
    index = {ball: k for k, ball in enumerate(ids)}
    rows = [
        (index[ball], s.t0, s.t1, *s.pos, *s.vel, s.decel, math.hypot(*s.vel))
        for ball in ids
        for s in outcome.segments[ball]
    ]
    touched = np.zeros((len(ids), len(ids)), dtype=np.bool_)
    for event in outcome.events:
        if event.kind == "ball":
            a, b = sorted(index[i] for i in event.ids)
            touched[a, b] = True
    moving = np.array(
        [any(s.vel != (0.0, 0.0) for s in outcome.segments[ball]) for ball in ids], dtype=np.bool_
    )
    return ids, np.array(rows, dtype=float).reshape(-1, 9), touched, moving
