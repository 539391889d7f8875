"""The stability tally of :mod:`bpb_tasks.billiards.stability_batch` in one compiled call.

:func:`tally_copies` runs each perturbed copy through the kernel and folds its event log and
final state into the tally at once: label bit masks per copy (cue contacts, cue walls, pocketed
balls; one bit per ball index or wall), XORed against the nominal masks, and the largest distance
of a ball from its nominal final position. No per-copy table leaves compiled code.
"""

from __future__ import annotations

import numpy as np

from bpb_tasks.simulators.analytic.kernel import run_arrays
from bpb_tasks.simulators.analytic.kernel_predict import BALL, WALL, Arr
from bpb_tasks.simulators.analytic.kernel_roots import jit


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
    per group, the number of copies with any flip, the Q3 spread, and the index of the first copy
    that exceeded ``max_events`` (-1 when none did; the tally then stops there).
    """
    copies = pos.shape[0] // n if n else 0
    counts = np.zeros(3, dtype=np.int64)
    unions = np.zeros(3, dtype=np.int64)
    masks = np.zeros(3, dtype=np.int64)
    any_flip = 0
    spread = 0.0
    for c in range(copies):
        a, b = c * n, (c + 1) * n
        events, _, final, status = run_arrays(pos[a:b], vel[a:b], prm, pockets, horizon, max_events)
        if status != 0:
            return counts, unions, any_flip, spread, c
        masks[:] = 0
        if cue >= 0:
            for r in range(events.shape[0]):
                kind, p, q, wall = events[r, 1], int(events[r, 2]), int(events[r, 3]), events[r, 4]
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
    return counts, unions, any_flip, spread, -1
