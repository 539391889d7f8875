"""The order a run sends its calls in: every (scene, task) pair shuffled with a seeded generator.

Sent in dataset order, a run stopped early (``--max-cost``, Ctrl-C, a quota) holds the first
horizons complete and the last ones empty, and any per-horizon table is made of missing answers.
Shuffled, any prefix of the run is a uniform sample of the pairs, so a partial run's accuracy by
horizon, scene or task estimates the full run's. The whole plan is shuffled before finished pairs
are dropped, so a resumed run goes on in the same order; the seed is kept in ``run.json``.
"""

from __future__ import annotations

import random
from collections.abc import Sequence

from bpb_core.runner.scenes import SceneRef

Pair = tuple[SceneRef, str, int]
"""A scene, a task and the epoch (1 unless ``--epochs`` asks for repeated samples)."""


def call_order(
    refs: Sequence[SceneRef],
    tasks: Sequence[str],
    done: set[tuple[str, str, int]],
    seed: int,
    epochs: int = 1,
) -> list[Pair]:
    """The (scene, task, epoch) samples still to send, in the run's seeded random order.

    Args:
        refs: The scenes the run asks about.
        tasks: The tasks asked about each scene.
        done: ``(scene_id, task, epoch)`` samples already finished (dropped from the result).
        seed: The order seed (recorded in ``run.json``; a resume reuses it).
        epochs: Samples per (scene, task).

    Returns:
        A uniform random permutation of the samples not yet done.
    """
    pairs = [(ref, task, e) for e in range(1, epochs + 1) for ref in refs for task in tasks]
    random.Random(f"bpb-call-order:{seed}").shuffle(pairs)
    return [(r, t, e) for r, t, e in pairs if (r.scene_id, t, e) not in done]
