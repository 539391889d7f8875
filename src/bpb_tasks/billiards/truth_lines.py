"""The fast path of ``bpb simulate``: ``final.json`` lines straight from the compiled kernel's
arrays, without building :class:`~bpb_tasks.billiards.truth.FinalState` models or event objects.

The lines are the bytes of ``FinalState.model_dump_json()`` (same keys in the same order, same
number formatting; a test compares): every number of a chunk is formatted by one call of
pydantic-core's own writer, and the lines are put together from those pieces. Only the analytic
simulator on float64 with the kernel (and msgspec, which reads the texts) installed has this path;
everything else goes through the models.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Sequence
from typing import Any

import numpy as np
from pydantic_core import to_json

from bpb_core.interfaces import Simulator
from bpb_tasks.billiards.scene import WALLS, Scene

KINDS = ("ball", "wall", "pocket", "stop")
CHUNK = 512  # scenes per compiled call
BATCH_MIN = 256
"""Fewer texts than this go the ordinary way unless the kernel is loaded already: loading it
costs about a second, which the fast path saves back only over a few thousand scenes."""

_WALL_NAMES = {**{i: f'"{w}"' for i, w in enumerate(WALLS)}, -1: "null"}
_Q2 = [
    ",".join(
        f'{{"wall":"{w}","answer":"{"T" if bits >> k & 1 else "F"}"}}' for k, w in enumerate(WALLS)
    )
    for bits in range(1 << len(WALLS))
]  # the q2 list for each set of walls the cue ball touched, as bits


def text_lines(
    texts: Sequence[bytes], simulator: Simulator, horizon: float | None
) -> list[str | None] | None:
    """``final.json`` lines of ``init.json`` texts read by
    :func:`~bpb_tasks.billiards.scene_text.light_scene` (no pydantic model per scene): ``None``
    for a text it does not take, or as a whole when ``simulator`` has no fast path."""
    if not _fast(simulator, worth_loading=len(texts) >= BATCH_MIN):
        return None
    from bpb_tasks.billiards.scene_text import text_groups

    lines: list[str | None] = [None] * len(texts)
    for group in text_groups(texts):
        _group_lines(group, simulator, horizon, lines)
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
        _group_lines(group, simulator, horizon, lines)
    return [line for line in lines if line is not None]


def _group_lines(
    group: Any, simulator: Any, horizon: float | None, lines: list[str | None]
) -> None:
    """Simulate ``group`` (a :class:`~bpb_tasks.billiards.scene_text.SceneGroup`) in chunks and
    put each scene's line at its member position in ``lines``."""
    from bpb_tasks.billiards.scene_text import LightScene
    from bpb_tasks.simulators.analytic.compiled import table_params
    from bpb_tasks.simulators.analytic.engine import SimulationError
    from bpb_tasks.simulators.analytic.kernel import run_many_arrays

    table, physics, pockets = group.parts
    shape = LightScene("", 1.0, table, physics, pockets, [])
    prm, centres = table_params(shape)  # type: ignore[arg-type]  # reads only the three parts
    n = group.ids.shape[1]
    name = to_json(simulator.name).decode()
    for at in range(0, len(group.members), CHUNK):
        scenes = group.scenes[at : at + CHUNK]
        k = len(scenes)
        ends = [s.horizon if horizon is None else horizon for s in scenes]
        pos = np.ascontiguousarray(group.pos[at : at + k].reshape(-1, 2))
        vel = np.ascontiguousarray(group.vel[at : at + k].reshape(-1, 2))
        starts = np.arange(k + 1, dtype=np.int64) * n
        final, status, events = run_many_arrays(
            pos, vel, starts, prm, centres, np.array(ends, dtype=float), simulator.max_events
        )
        if status.any():
            raise SimulationError(f"more than {simulator.max_events} events in a scene")
        made = _lines(scenes, group.ids[at : at + k], ends, final, events, name)
        for member, line in zip(group.members[at : at + k], made, strict=True):
            lines[member] = line


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
    scenes: Sequence[Any],
    ids: np.ndarray,
    ends: list[float],
    final: np.ndarray,
    events: np.ndarray,
    simulator: str,
) -> list[str]:
    """The lines of one compiled call's results (``ids``: ``(k, n)``, ascending per scene, so
    index 0 is the cue ball, id 0).

    Every number of the chunk, in the order the lines hold them, is formatted by one
    pydantic-core call; each line's text around its numbers is a template (``%s`` where a
    number goes) put together from cached pieces (the predictions for a set of ids and pocketed
    balls, each event for its kind, ids and wall, the q1 and q2 lists); one ``%`` over the
    whole chunk fills the numbers in. No string is made per number or per record."""
    k, n = ids.shape
    scene = events[:, 0].astype(np.int64)
    kind, a, b, wall = (events[:, c].astype(np.int64) for c in (2, 3, 4, 5))
    pair = b >= 0
    flat_ids = ids.ravel()
    id_a = flat_ids[scene * n + a]
    id_b = np.where(pair, flat_ids[scene * n + np.maximum(b, 0)], -1)
    alive = final[:, 2] != 0
    numbers = _numbers(np.array(ends, dtype=float), final, alive, events, scene, pair)
    values = to_json(numbers.tolist()).decode()[1:-1].split(",")
    found = _EVENTS.get
    records = [
        found(key) or _event(key)
        for key in zip(kind.tolist(), id_a.tolist(), id_b.tolist(), wall.tolist(), strict=True)
    ]
    cue = (a == 0) | (pair & (b == 0))
    walls = np.zeros(k, dtype=np.int64)
    hit = cue & ~pair & (wall >= 0)
    np.bitwise_or.at(walls, scene[hit], np.left_shift(1, wall[hit]))
    q1 = _q1_texts(ids, scene[cue & pair], np.where(a == 0, b, a)[cue & pair])
    bounds = np.searchsorted(scene, np.arange(k + 1)).tolist()
    tail = f'],"stability":null,"simulator":{simulator.replace("%", "%%")}}}'
    template = "\n".join(
        f'{{"scene_id":{_string(s.scene_id)},"horizon":%s,"q1":[{q}],"q2":[{_Q2[w]}],'
        f'"predictions":[{p}],"events":[{",".join(records[lo:hi])}{tail}'
        for s, q, w, p, lo, hi in zip(
            scenes, q1, walls.tolist(), _predictions(ids, alive.reshape(k, n)), bounds[:-1],
            bounds[1:], strict=True,
        )
    )  # fmt: skip
    return (template % tuple(values)).split("\n")


def _numbers(
    ends: np.ndarray,
    final: np.ndarray,
    alive: np.ndarray,
    events: np.ndarray,
    scene: np.ndarray,
    pair: np.ndarray,
) -> np.ndarray:
    """The numbers of each scene's line in the order the line holds them: its horizon, the
    rounded final position of each ball not pocketed, then each event's time and position(s)
    (two for a ball-ball contact, one otherwise). Three sections already in scene order are
    interleaved by computing where each value goes."""
    k, n = len(ends), final.shape[0] // len(ends)
    preds = round4(final[:, :2].ravel()).reshape(-1, 2)[alive].ravel()
    pred_scene = np.repeat(np.arange(k), n)[alive]
    taken = np.ones((len(events), 5), dtype=bool)
    taken[:, 3:] = pair[:, None]
    ev = events[:, [1, 6, 7, 8, 9]][taken]
    ev_scene = np.repeat(scene, taken.sum(axis=1))
    pred_count = 2 * np.bincount(pred_scene, minlength=k)
    ev_count = np.bincount(ev_scene, minlength=k)
    start = np.cumsum(1 + pred_count + ev_count) - (1 + pred_count + ev_count)
    out = np.empty(k + len(preds) + len(ev))
    out[start] = ends
    first_pred = np.cumsum(pred_count) - pred_count
    where = np.arange(len(preds)) + np.repeat(start + 1 - first_pred, pred_count)
    out[where] = preds
    first_ev = np.cumsum(ev_count) - ev_count
    where = np.arange(len(ev)) + np.repeat(start + 1 + pred_count - first_ev, ev_count)
    out[where] = ev
    return out


_EVENTS: dict[tuple[int, int, int, int], str] = {}


def _event(key: tuple[int, int, int, int]) -> str:
    """The template of an event record (``%s`` for its time and coordinates) by kind, ids and
    wall (second id -1 when there is one ball)."""
    kind, i, j, wall = key
    if j >= 0:
        found = (
            f'{{"t":%s,"kind":"ball","ids":[{i},{j}],"wall":null,"positions":[[%s,%s],[%s,%s]]}}'
        )
    else:
        found = (
            f'{{"t":%s,"kind":"{KINDS[kind]}","ids":[{i}],"wall":{_WALL_NAMES[wall]},'
            f'"positions":[[%s,%s]]}}'
        )
    if len(_EVENTS) < 4096:
        _EVENTS[key] = found
    return found


_PREDICTIONS: dict[tuple[tuple[int, ...], tuple[bool, ...]], str] = {}


def _predictions(ids: np.ndarray, alive: np.ndarray) -> list[str]:
    """The template of each scene's predictions list (``%s`` for the coordinates of each ball
    not pocketed) for ``ids`` and ``alive`` (both ``(k, n)``)."""
    rows = list(map(tuple, alive.tolist()))
    if (ids == ids[0]).all():  # the usual case: every scene has the same ids
        same = tuple(ids[0].tolist())
        keys = [(same, r) for r in rows]
    else:
        keys = list(zip(map(tuple, ids.tolist()), rows, strict=True))
    found = _PREDICTIONS.get
    return [found(key) or _prediction(key) for key in keys]


def _prediction(key: tuple[tuple[int, ...], tuple[bool, ...]]) -> str:
    ids, alive = key
    found = ",".join(
        f'{{"id":{i},"pos":[%s,%s]}}' if up else f'{{"id":{i},"pos":null}}'
        for i, up in zip(ids, alive, strict=True)
    )
    if len(_PREDICTIONS) < 4096:
        _PREDICTIONS[key] = found
    return found


def _q1_texts(ids: np.ndarray, scene: np.ndarray, touched: np.ndarray) -> list[str]:
    """The q1 list of each scene of ``ids`` whose cue ball touched the balls at indices
    ``touched`` (of scenes ``scene``)."""
    k, n = ids.shape
    hits = np.zeros((k, n), dtype=bool)
    hits[scene, touched] = True
    rows = hits[:, 1:].tolist()
    if (ids == ids[0]).all():  # the usual case: every scene has the same ids
        same = tuple(ids[0].tolist())
        return [_q1(same, tuple(r)) for r in rows]
    return [_q1(tuple(own), tuple(r)) for own, r in zip(ids.tolist(), rows, strict=True)]


def _string(value: str) -> str:
    """``value`` as pydantic-core writes it (quoted as it is when nothing in it needs escaping),
    with ``%`` doubled for the line's template."""
    plain = value.isascii() and value.isprintable()
    if plain and not ('"' in value or "\\" in value or "%" in value):
        return f'"{value}"'
    return to_json(value).decode().replace("%", "%%")


_Q1: dict[tuple[tuple[int, ...], tuple[bool, ...]], str] = {}


def _q1(ids: tuple[int, ...], hits: tuple[bool, ...]) -> str:
    """The q1 list of a scene with ``ids`` (cue ball first) whose cue ball touched the others
    where ``hits`` is true."""
    key = (ids, hits)
    found = _Q1.get(key)
    if found is None:
        found = ",".join(
            f'{{"id":{i},"answer":"{"T" if hit else "F"}"}}'
            for i, hit in zip(ids[1:], hits, strict=True)
        )
        if len(_Q1) < 4096:
            _Q1[key] = found
    return found
