"""The fast path of ``bpb simulate``: ``final.json`` lines straight from the compiled kernel's
arrays, without building :class:`~bpb_tasks.billiards.truth.FinalState` models or event objects.

The lines hold the same content as ``FinalState.model_dump_json()`` (same keys in the same order,
equal numbers; a test compares them); only the analytic simulator on float64 with the kernel
available has this path, everything else goes through the models.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from pydantic_core import to_json

from bpb_core.interfaces import Simulator
from bpb_tasks.billiards.outcome import CUE_ID
from bpb_tasks.billiards.scene import WALLS, Scene
from bpb_tasks.billiards.scene_text import LightScene, light_scenes

KINDS = ("ball", "wall", "pocket", "stop")
CHUNK = 512  # scenes per compiled call


def text_lines(
    texts: Sequence[bytes], simulator: Simulator, horizon: float | None
) -> list[str | None] | None:
    """``final.json`` lines of ``init.json`` texts read by
    :func:`~bpb_tasks.billiards.scene_text.light_scene` (no pydantic model per scene): ``None``
    for a text it does not take, or as a whole when ``simulator`` has no fast path."""
    if not _fast(simulator, worth_loading=len(texts) >= BATCH_MIN):
        return None
    scenes = light_scenes(texts)
    taken = [s for s in scenes if s is not None]
    done = iter(truth_lines(taken, simulator, horizon) or [])
    return [None if s is None else next(done) for s in scenes]


BATCH_MIN = 256
"""Fewer texts than this go the ordinary way unless the kernel is loaded already: loading it
costs about a second, which the fast path saves back only over a few thousand scenes."""


def _fast(simulator: Simulator, *, worth_loading: bool = True) -> bool:
    """Whether ``simulator`` has the compiled path, and it is loaded or ``worth_loading``."""
    from bpb_tasks.simulators.analytic.engine import AnalyticSimulator

    if not isinstance(simulator, AnalyticSimulator) or not simulator.compiled:
        return False
    return worth_loading or simulator.kernel_loaded()


def truth_lines(
    scenes: Sequence[Scene | LightScene], simulator: Simulator, horizon: float | None
) -> list[str] | None:
    """``final.json`` lines of ``scenes`` or ``None`` when ``simulator`` has no fast path."""
    from bpb_tasks.simulators.analytic.engine import SimulationError

    if not _fast(simulator):
        return None
    assert hasattr(simulator, "max_events") and hasattr(simulator, "name")
    from bpb_tasks.simulators.analytic.compiled import KernelBudgetError, run_batch

    groups: dict[Any, list[int]] = {}
    for i, s in enumerate(scenes):
        key = (s.table, s.physics, s.pockets.radius, tuple(s.pockets.centers))
        groups.setdefault(key, []).append(i)
    lines: list[str] = [""] * len(scenes)
    for members in groups.values():
        for at in range(0, len(members), CHUNK):
            chunk = members[at : at + CHUNK]
            group: list[Any] = [scenes[i] for i in chunk]
            ends = [s.horizon if horizon is None else horizon for s in group]
            try:
                arrays, starts, final, events = run_batch(group, ends, simulator.max_events)
            except KernelBudgetError as exc:
                raise SimulationError(str(exc)) from None
            per_scene: list[list[list[float]]] = [[] for _ in group]
            for row in events.tolist():
                per_scene[int(row[0])].append(row)
            rows = final.tolist()
            for j, s in enumerate(group):
                ids = arrays[j][0]
                own = rows[int(starts[j]) : int(starts[j + 1])]
                lines[chunk[j]] = _line(s, ids, own, per_scene[j], ends[j], simulator.name)
    return lines


def _line(
    scene: Scene | LightScene,
    ids: list[int],
    final: list[list[float]],
    events: list[list[float]],
    horizon: float,
    simulator: str,
) -> str:
    contacts: set[int] = set()
    walls: set[str] = set()
    records = []
    for _, t, kind, a, b, wall, xa, ya, xb, yb in events:
        ia = ids[int(a)]
        if b >= 0:
            ib = ids[int(b)]
            if CUE_ID in (ia, ib):
                contacts.add(ib if ia == CUE_ID else ia)
            records.append(
                {"t": t, "kind": "ball", "ids": [ia, ib], "wall": None,
                 "positions": [[xa, ya], [xb, yb]]}
            )  # fmt: skip
            continue
        name = WALLS[int(wall)] if wall >= 0 else None
        if name is not None and ia == CUE_ID:
            walls.add(name)
        records.append(
            {"t": t, "kind": KINDS[int(kind)], "ids": [ia], "wall": name, "positions": [[xa, ya]]}
        )
    truth = {
        "scene_id": scene.scene_id,
        "horizon": horizon,
        "q1": [{"id": i, "answer": "T" if i in contacts else "F"} for i in ids if i != CUE_ID],
        "q2": [{"wall": w, "answer": "T" if w in walls else "F"} for w in WALLS],
        "predictions": [
            {"id": i, "pos": [round(r[0], 4) + 0.0, round(r[1], 4) + 0.0] if r[2] else None}
            for i, r in zip(ids, final, strict=True)
        ],
        "events": records,
        "stability": None,
        "simulator": simulator,
    }
    return to_json(truth).decode()  # pydantic's own writer: the model path's bytes
