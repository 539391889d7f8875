"""The fast path of ``bpb simulate``: ``final.json`` lines straight from the compiled kernel's
arrays, without building :class:`~bpb_tasks.billiards.truth.FinalState` models or event objects.

The lines are the bytes of ``FinalState.model_dump_json()`` (same keys in the same order, same
number formatting; a test compares): every number of a chunk is formatted by one call of
pydantic-core's own writer, and the lines are put together from those pieces by compiled code
(:mod:`bpb_tasks.billiards.truth_bytes`). Only the analytic simulator on float64 with the
kernel (and msgspec, which reads the texts) installed has this path; everything else goes through
the models.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Sequence
from typing import Any

import numpy as np
from pydantic_core import to_json

from bpb_core.interfaces import Simulator
from bpb_tasks.billiards.scene import Scene

CHUNK = 512  # scenes per compiled call
BATCH_MIN = 256
"""Fewer texts than this go the ordinary way unless the kernel is loaded already: loading it
costs about a second, which the fast path saves back only over a few thousand scenes."""


def text_lines(
    texts: Sequence[bytes], simulator: Simulator, horizon: float | None, *, block: bool = False
) -> list[str | None] | bytes | None:
    """``final.json`` lines of ``init.json`` texts read by
    :func:`~bpb_tasks.billiards.scene_text.light_scene` (no pydantic model per scene): ``None``
    for a text it does not take, or as a whole when ``simulator`` has no fast path. With
    ``block``, when every text is taken and they share one table (the usual case), all the
    lines as one UTF-8 block joined by newlines: the compiled code writes bytes, and decoding
    and splitting them only for ``bpb simulate`` to join and encode them again cost about a
    microsecond per scene."""
    if not _fast(simulator, worth_loading=len(texts) >= BATCH_MIN):
        return None
    from bpb_tasks.billiards.scene_scan import text_groups
    from bpb_tasks.billiards.scene_text import SceneGroup

    groups: list[SceneGroup] = text_groups(texts)
    if block and len(groups) == 1 and groups[0].members == list(range(len(texts))):
        return b"\n".join(_group_blocks(groups[0], simulator, horizon))
    lines: list[str | None] = [None] * len(texts)
    for group in groups:
        _put(group, _group_blocks(group, simulator, horizon), lines)
    return lines


def _fast(simulator: Simulator, *, worth_loading: bool = True) -> bool:
    """Whether ``simulator`` has the compiled path, and it is loaded or ``worth_loading``."""
    from bpb_tasks.simulators.analytic.engine import AnalyticSimulator

    if not isinstance(simulator, AnalyticSimulator) or not simulator.compiled:
        return False
    if importlib.util.find_spec("msgspec") is None:
        return False
    return worth_loading or simulator.kernel_loaded()


def truth_lines(
    scenes: Sequence[Scene], simulator: Simulator, horizon: float | None
) -> list[str] | None:
    """``final.json`` lines of validated ``scenes``, or ``None`` when ``simulator`` has no fast
    path."""
    if not _fast(simulator):
        return None
    from bpb_tasks.billiards.scene_text import scene_groups

    lines: list[str | None] = [None] * len(scenes)
    for group in scene_groups(scenes, checks=False):
        _put(group, _group_blocks(group, simulator, horizon), lines)
    return [line for line in lines if line is not None]


def _put(group: Any, blocks: list[bytes], lines: list[str | None]) -> None:
    """Each line of ``blocks`` (``group``'s, in member order) at its member position."""
    made = b"\n".join(blocks).decode().split("\n")
    for member, line in zip(group.members, made, strict=True):
        lines[member] = line


def _group_blocks(group: Any, simulator: Any, horizon: float | None) -> list[bytes]:
    """Simulate ``group`` (a :class:`~bpb_tasks.billiards.scene_text.SceneGroup`) in chunks:
    the lines of each chunk as one block (UTF-8, joined by newlines)."""
    from bpb_tasks.billiards.scene_text import LightScene
    from bpb_tasks.simulators.analytic.compiled import table_params
    from bpb_tasks.simulators.analytic.engine import SimulationError
    from bpb_tasks.simulators.analytic.kernel import run_many_arrays

    table, physics, pockets = group.parts
    shape = LightScene("", 1.0, table, physics, pockets, [])
    prm, centres = table_params(shape)  # type: ignore[arg-type]  # reads only the three parts
    n = group.ids.shape[1]
    name = to_json(simulator.name).decode()
    blocks = []
    for at in range(0, len(group.members), CHUNK):
        names = group.names[at : at + CHUNK]
        k = len(names)
        ends = group.horizons[at : at + k] if horizon is None else np.full(k, float(horizon))
        pos = np.ascontiguousarray(group.pos[at : at + k].reshape(-1, 2))
        vel = np.ascontiguousarray(group.vel[at : at + k].reshape(-1, 2))
        starts = np.arange(k + 1, dtype=np.int64) * n
        final, status, events = run_many_arrays(
            pos, vel, starts, prm, centres, ends, simulator.max_events
        )
        if status.any():
            raise SimulationError(f"more than {simulator.max_events} events in a scene")
        blocks.append(_lines(names, group.ids[at : at + k], ends, final, events, name))
    return blocks


def round4(values: np.ndarray) -> np.ndarray:
    """``round(v, 4) + 0.0`` of every value, bit for bit, on arrays: ``rint(v * 1e4) / 1e4`` is
    that (both are the double nearest to the decimal m / 10**4, by IEEE division) whenever the
    scaled value is not within 1e-6 of a rounding tie, where its own rounding error could move
    it to the other side; those values, and huge or non-finite ones, go through ``round``."""
    with np.errstate(invalid="ignore", over="ignore"):
        scaled = values * 1e4
        out = np.rint(scaled) / 1e4 + 0.0
        doubtful = ~(np.abs(values) < 1e9) | (np.abs(scaled - np.floor(scaled) - 0.5) < 1e-6)
    for i in np.flatnonzero(doubtful).tolist():
        value = float(values[i])
        out[i] = round(value, 4) + 0.0 if np.isfinite(value) else value
    return out


def _lines(
    names: list[str],
    ids: np.ndarray,
    ends: np.ndarray,
    final: np.ndarray,
    events: np.ndarray,
    simulator: str,
) -> bytes:
    """The lines of one compiled call's results, as one block joined by newlines (``ids``:
    ``(k, n)``, ascending per scene, so index 0 is the cue ball, id 0): every number formatted
    by one pydantic-core call, the labels worked out on arrays, the lines put together as bytes
    by compiled code (:func:`~bpb_tasks.billiards.truth_bytes.assemble`)."""
    from bpb_tasks.billiards.truth_bytes import assemble

    k, n = ids.shape
    scene = events[:, 0].astype(np.int64)
    kind, a, b, wall = (events[:, c].astype(np.int64) for c in (2, 3, 4, 5))
    pair = b >= 0
    flat_ids = ids.ravel()
    id_a = flat_ids[scene * n + a]
    id_b = np.where(pair, flat_ids[scene * n + np.maximum(b, 0)], -1)
    xy, times_and_places = round4(final[:, :2].ravel()), events[:, [1, 6, 7, 8, 9]].ravel()
    numbers = np.concatenate([ends, xy, times_and_places])
    cue = (a == 0) | (pair & (b == 0))
    walls = np.zeros(k, dtype=np.int64)
    hit = cue & ~pair & (wall >= 0)
    np.bitwise_or.at(walls, scene[hit], np.left_shift(1, wall[hit]))
    hits = np.zeros((k, n), dtype=np.bool_)
    hits[scene[cue & pair], np.where(a == 0, b, a)[cue & pair]] = True
    bounds = np.searchsorted(scene, np.arange(k + 1))
    return assemble(
        to_json(numbers.tolist()),
        ids,
        final[:, 2] != 0,
        hits,
        walls,
        (kind, id_a, id_b, wall, bounds),
        names,
        simulator,
    )
