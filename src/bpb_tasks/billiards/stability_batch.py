"""The perturbed copies of the stability annotation in one compiled call, tallied on arrays.

:func:`kernel_tally` runs every copy through the kernel's batch entry point and turns its raw
event and final-state rows into bit masks per copy (cue contacts, cue walls, pocketed balls, one
bit per ball index or wall), so flips are XORs against the nominal masks and the Q3 spread is one
array expression; no per-copy Python objects are built. It gives the same tally as running each
copy through :meth:`~bpb_tasks.simulators.analytic.AnalyticSimulator.run` (a test compares).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bpb_tasks.billiards.outcome import CUE_ID, Outcome
from bpb_tasks.billiards.scene import WALLS, Scene


@dataclass
class Tally:
    """Flip counts per label group, copies with any flip, flipped label names, Q3 spread."""

    counts: dict[str, int]
    any_flip: int = 0
    flips: set[str] = field(default_factory=set)
    spread: float = 0.0


def kernel_tally(
    scene: Scene,
    base: Outcome,
    ids: list[int],
    pos: np.ndarray,
    vel: np.ndarray,
    max_events: int,
) -> Tally:
    """Tally the copies ``pos``/``vel`` (``(k, n, 2)``, balls in ``ids`` order) of ``scene``
    against its nominal outcome ``base``."""
    from bpb_tasks.simulators.analytic.compiled import KernelBudgetError, table_params
    from bpb_tasks.simulators.analytic.kernel import run_many_arrays

    k, n = pos.shape[0], pos.shape[1]
    prm, pockets = table_params(scene)
    final, status, events = run_many_arrays(
        np.ascontiguousarray(pos.reshape(-1, 2)),
        np.ascontiguousarray(vel.reshape(-1, 2)),
        np.arange(k + 1, dtype=np.int64) * n,
        prm,
        pockets,
        np.full(k, float(base.horizon)),
        max_events,
    )
    if status.any():
        raise KernelBudgetError(f"copy {int(np.argmax(status))}: more than {max_events} events")
    masks = _masks(events, final, ids, k, n)
    reference = _nominal(base, ids)
    tally = Tally(counts={})
    changed = np.zeros(k, dtype=bool)
    for (group, prefix, names), got, ref in zip(_groups(ids), masks, reference, strict=True):
        xor = got ^ ref
        tally.counts[group] = int((xor != 0).sum())
        changed |= xor != 0
        union = int(np.bitwise_or.reduce(xor)) if k else 0
        tally.flips.update(f"{prefix}:{names[j]}" for j in range(len(names)) if union >> j & 1)
    tally.any_flip = int(changed.sum())
    tally.spread = _spread(base, ids, final[:, :2].reshape(k, n, 2), final[:, 2].reshape(k, n))
    return tally


def _groups(ids: list[int]) -> list[tuple[str, str, list[object]]]:
    """Group name, flip-name prefix and the label item of each bit."""
    balls: list[object] = list(ids)
    return [("q1", "q1", balls), ("q2", "q2", list(WALLS)), ("pocketed", "q3:pocket", balls)]


def _masks(
    events: np.ndarray, final: np.ndarray, ids: list[int], k: int, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    contacts = np.zeros(k, dtype=np.int64)
    walls = np.zeros(k, dtype=np.int64)
    if CUE_ID in ids and len(events):
        cue = ids.index(CUE_ID)
        copy = events[:, 0].astype(np.int64)
        kind, wall = events[:, 2], events[:, 5].astype(np.int64)
        a, b = events[:, 3].astype(np.int64), events[:, 4].astype(np.int64)
        hit = (kind == 0) & ((a == cue) | (b == cue))
        other = np.where(a == cue, b, a)
        np.bitwise_or.at(contacts, copy[hit], np.left_shift(1, other[hit]))
        bounce = (kind == 1) & (a == cue) & (wall >= 0)
        np.bitwise_or.at(walls, copy[bounce], np.left_shift(1, wall[bounce]))
    gone = final[:, 2].reshape(k, n) == 0
    pocketed = (gone * np.left_shift(1, np.arange(n, dtype=np.int64))).sum(axis=1)
    return contacts, walls, pocketed.astype(np.int64)


def _nominal(base: Outcome, ids: list[int]) -> tuple[int, int, int]:
    index = {ball: j for j, ball in enumerate(ids)}
    contacts = sum(1 << index[i] for i in base.cue_contacts())
    walls = sum(1 << WALLS.index(w) for w in base.cue_walls())
    pocketed = sum(1 << index[i] for i, p in base.positions.items() if p is None)
    return contacts, walls, pocketed


def _spread(base: Outcome, ids: list[int], final: np.ndarray, alive: np.ndarray) -> float:
    nominal = np.array([base.positions[i] or (np.nan, np.nan) for i in ids], dtype=float)
    both = (alive > 0) & ~np.isnan(nominal[:, 0])
    if not both.any():
        return 0.0
    gaps = np.hypot(final[..., 0] - nominal[:, 0], final[..., 1] - nominal[:, 1])
    return float(gaps[both].max())
