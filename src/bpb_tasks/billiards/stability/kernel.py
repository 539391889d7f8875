"""The stability annotation's perturbed copies in the compiled kernel.

:func:`copy_labels` runs every copy of a scene through the kernel in one call (:func:`copy_masks`)
and gives what the Python engine's runs give
:func:`~bpb_tasks.billiards.stability.annotation.tally_copies`: each copy's labels (``None``
when it did not finish within its event budget) and final positions. In compiled code the labels
are bit masks (cue contacts, cue walls, pocketed balls; one bit per ball index or wall), so a
scene holds at most :data:`~bpb_tasks.billiards.stability.annotation.KERNEL_MAX_BALLS` balls here.
"""

from __future__ import annotations

import numpy as np

from bpb_tasks.billiards.scene.model import WALLS, Scene
from bpb_tasks.billiards.stability.annotation import Labels
from bpb_tasks.billiards.truth.outcome import CUE_ID
from bpb_tasks.simulators.analytic.kernel import (
    BALL,
    WALL,
    Arr,
    buffers,
    jit,
    run_into,
    table_params,
)


def copy_labels(
    scene: Scene, ids: list[int], pos: np.ndarray, vel: np.ndarray, max_events: int
) -> tuple[list[Labels | None], np.ndarray]:
    """The labels of the copies ``pos``/``vel`` (``(k, n, 2)``, balls in ``ids`` order) of
    ``scene`` run to its horizon (``None`` for a copy needing more than ``max_events``
    events), and their ``(k, n, 2)`` final positions (NaN where pocketed or unfinished)."""
    prm, pockets = table_params(scene)
    masks, finished, finals = copy_masks(
        np.ascontiguousarray(pos.reshape(-1, 2)),
        np.ascontiguousarray(vel.reshape(-1, 2)),
        pos.shape[1],
        prm,
        pockets,
        float(scene.horizon),
        max_events,
        ids.index(CUE_ID) if CUE_ID in ids else -1,
    )
    decoded: dict[tuple[int, int, int], Labels] = {}
    labels: list[Labels | None] = []
    for row, done in zip(masks.tolist(), finished.tolist(), strict=True):
        key = (row[0], row[1], row[2])
        if key not in decoded:
            decoded[key] = (_items(row[0], ids), _items(row[1], WALLS), _items(row[2], ids))
        labels.append(decoded[key] if done else None)
    return labels, finals


def _items(mask: int, names: list[int] | tuple[str, ...]) -> frozenset:  # type: ignore[type-arg]
    return frozenset(name for j, name in enumerate(names) if mask >> j & 1)


@jit
def copy_masks(
    pos: Arr,
    vel: Arr,
    n: int,
    prm: Arr,
    pockets: Arr,
    horizon: float,
    max_events: int,
    cue: int,
) -> tuple[Arr, Arr, Arr]:
    """Run the copies of ``n`` balls stacked in ``pos``/``vel`` (``(copies * n, 2)``; ``cue``
    the cue ball's index, -1 without one). Returns per copy its ``(contacts, walls,
    pocketed)`` masks, whether it finished within ``max_events`` events, and its balls' final
    positions (NaN where pocketed or unfinished)."""
    copies = pos.shape[0] // n if n else 0
    masks = np.zeros((copies, 3), dtype=np.int64)
    finished = np.zeros(copies, dtype=np.bool_)
    finals = np.full((copies, n, 2), np.nan)
    work = buffers(n)  # one set of working arrays for every copy
    events, final = work[4], work[6]
    for c in range(copies):
        a, b = c * n, (c + 1) * n
        if run_into(work, pos[a:b], vel[a:b], prm, pockets, horizon, max_events, False) != 0:
            continue
        finished[c] = True
        if cue >= 0:
            for row in events:
                kind, p, q, wall = row[1], int(row[2]), int(row[3]), row[4]
                if kind == BALL and (p == cue or q == cue):
                    masks[c, 0] |= np.int64(1) << (q if p == cue else p)
                elif kind == WALL and p == cue and wall >= 0:
                    masks[c, 1] |= np.int64(1) << int(wall)
        for j in range(n):
            if final[j, 2] == 0:
                masks[c, 2] |= np.int64(1) << j
            else:
                finals[c, j, 0], finals[c, j, 1] = final[j, 0], final[j, 1]
    return masks, finished, finals
