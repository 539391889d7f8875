"""Scenes in, outcomes out: the Python side of the compiled event kernel.

:func:`kernel_outcome` simulates one :class:`~bpb_tasks.billiards.scene.Scene` with
:func:`~bpb_tasks.simulators.analytic.kernel.run_arrays` and builds the same
:class:`~bpb_tasks.billiards.outcome.Outcome` the reference engine does. :func:`outcomes_many`
is the batch API behind ``AnalyticSimulator.run_many``: many scenes in one compiled call, their
outcomes without motion pieces; :func:`simulate_many` returns only what labels and final
positions need (no event objects).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bpb_core.errors import BpbError
from bpb_tasks.billiards.outcome import Event, Outcome, Segment
from bpb_tasks.billiards.scene import WALLS, Scene
from bpb_tasks.simulators.analytic.kernel import run_arrays, run_many_arrays
from bpb_tasks.simulators.analytic.kernel_roots import HAVE_NUMBA

KINDS = ("ball", "wall", "pocket", "stop")
SceneArrays = tuple[list[int], np.ndarray, np.ndarray]
AVAILABLE = HAVE_NUMBA


class KernelBudgetError(BpbError):
    """The compiled kernel exceeded its event budget."""


def table_params(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's table constants and pocket centres of ``scene`` (same arithmetic as the
    reference ``Predictor``); shared by the calls for scenes of one table, physics and pockets
    (a generated scene's nominal run, perturbed copies and horizon gap all take them): read
    them, never write."""
    table, physics, pockets = scene.table, scene.physics, scene.pockets
    kept = _PARAMS.get((id(table), id(physics), id(pockets)))
    if kept is not None and kept[0] == pockets.centers:  # the list could change in place
        return kept[1]
    made = _table_params(table, physics, pockets)
    if len(_PARAMS) >= 64:
        _PARAMS.clear()
    _PARAMS[id(table), id(physics), id(pockets)] = (list(pockets.centers), made, scene)
    return made


_PARAMS: dict[tuple[int, int, int], tuple[list[Any], tuple[np.ndarray, np.ndarray], Any]] = {}
""":func:`table_params` by the ids of a scene's table, physics and pockets, with the pocket
centres they were made from and the scene (holding the three, so their ids stay theirs)."""


def _table_params(table: Any, phys: Any, pockets: Any) -> tuple[np.ndarray, np.ndarray]:
    radius = phys.ball_radius
    decel = phys.mu * phys.g
    r = pockets.radius
    prm = np.array(
        [
            decel,
            decel / 2,
            4 * radius * radius,
            2 * radius,
            1e-9,
            radius,
            table.width - radius,
            radius,
            table.height - radius,
            phys.wall_restitution,
            r,
            r * r,
        ]
    )
    return prm, np.array(pockets.centers, dtype=float).reshape(-1, 2)


def scene_arrays(scene: Scene) -> SceneArrays:
    """Ball ids (sorted), positions and velocities of ``scene``; the last scene's are kept for
    its next call (its nominal run, perturbed copies and horizon gap): read them, never
    write."""
    global _LAST
    last = _LAST
    if last[0] is scene and last[1] == scene.balls:  # the list could change in place
        return last[2]
    balls = sorted(scene.balls, key=lambda b: b.id)
    pos = np.array([b.pos for b in balls], dtype=float).reshape(-1, 2)
    vel = np.array([b.vel for b in balls], dtype=float).reshape(-1, 2)
    made = [b.id for b in balls], pos, vel
    _LAST = scene, list(scene.balls), made
    return made


_LAST: tuple[object, list[Any], SceneArrays] = (None, [], ([], np.zeros((0, 2)), np.zeros((0, 2))))
"""The scene :func:`scene_arrays` was last called for (held, so no other takes its id), its
balls and its arrays."""


def kernel_outcome(scene: Scene, horizon: float, max_events: int) -> Outcome:
    """Simulate ``scene`` to ``horizon`` with the kernel; the reference engine's Outcome."""
    ids, pos, vel = scene_arrays(scene)
    prm, pockets = table_params(scene)
    events, pieces, final, status = run_arrays(pos, vel, prm, pockets, float(horizon), max_events)
    if status:
        raise KernelBudgetError(f"more than {max_events} events before t={float(horizon)}")
    return build_outcome(ids, events, pieces, final, float(horizon), float(prm[0]))


def build_outcome(
    ids: Sequence[int],
    events: np.ndarray,
    pieces: np.ndarray,
    final: np.ndarray,
    horizon: float,
    decel: float,
) -> Outcome:
    """An :class:`Outcome` from the kernel's arrays."""
    log = _event_log(ids, events.tolist())
    rows = final.tolist()
    positions = {ids[i]: (r[0], r[1]) if r[2] else None for i, r in enumerate(rows)}
    per_ball: list[list[list[float]]] = [[] for _ in ids]
    for row in pieces.tolist():
        per_ball[int(row[0])].append(row)
    segments = {}
    for i, own in enumerate(per_ball):
        end = rows[i][3]
        segments[ids[i]] = tuple(
            Segment(
                p[1], own[j + 1][1] if j + 1 < len(own) else end, (p[2], p[3]), (p[4], p[5]), decel
            )
            for j, p in enumerate(own)
        )
    return Outcome(horizon, positions, log, segments)


def _event_log(ids: Sequence[int], rows: list[list[float]]) -> tuple[Event, ...]:
    """The events of the kernel's event rows ``(t, kind, a, b, wall, xa, ya, xb, yb)``, whose
    balls ``a`` and ``b`` are indices into ``ids``."""
    log = []
    for t, kind, a, b, wall, xa, ya, xb, yb in rows:
        if b >= 0:
            log.append(Event(t, "ball", (ids[int(a)], ids[int(b)]), None, ((xa, ya), (xb, yb))))
        else:
            name = WALLS[int(wall)] if wall >= 0 else None
            log.append(Event(t, KINDS[int(kind)], (ids[int(a)],), name, ((xa, ya),)))
    return tuple(log)


@dataclass(frozen=True)
class BatchResult:
    """Results of :func:`simulate_many` for scenes ``0..n-1``.

    Attributes:
        positions: Per scene, ball id to final centre (``None`` when pocketed).
        contacts: Per scene, ids of the balls the cue ball (id 0) touched.
        walls: Per scene, the walls the cue ball touched.
        events: Per scene, the number of events processed.
    """

    positions: list[dict[int, tuple[float, float] | None]]
    contacts: list[set[int]]
    walls: list[set[str]]
    events: list[int]


def simulate_many(
    scenes: Sequence[Scene], horizons: Sequence[float] | None = None, max_events: int = 100_000
) -> BatchResult:
    """Simulate many scenes in one compiled call (they must share table, physics and pockets).

    Raises:
        ValueError: The scenes do not share one table.
        KernelBudgetError: A scene exceeded ``max_events``.
    """
    if not scenes:
        return BatchResult([], [], [], [])
    arrays, starts, final, events = run_batch(scenes, horizons, max_events)
    return _batch(arrays, starts, final, events)


def outcomes_many(
    scenes: Sequence[Scene], horizon: float | None = None, max_events: int = 100_000
) -> list[Outcome]:
    """The outcomes of many scenes (sharing table, physics and pockets) run to ``horizon``
    (default: their own) in one compiled call: final positions and events, and no motion
    pieces (``segments`` empty: nothing to draw from them).

    Raises:
        ValueError: The scenes do not share one table.
        KernelBudgetError: A scene exceeded ``max_events``.
    """
    if not scenes:
        return []
    ends = [s.horizon if horizon is None else horizon for s in scenes]
    arrays, starts, final, events = run_batch(scenes, ends, max_events)
    rows = final.tolist()
    bounds = np.searchsorted(events[:, 0], np.arange(len(scenes) + 1)).tolist()  # in scene order
    event_rows = events[:, 1:].tolist()
    outcomes = []
    for k, ((ids, _, _), a, b) in enumerate(
        zip(arrays, starts[:-1].tolist(), starts[1:].tolist(), strict=True)
    ):
        positions = {i: (r[0], r[1]) if r[2] else None for i, r in zip(ids, rows[a:b], strict=True)}
        log = _event_log(ids, event_rows[bounds[k] : bounds[k + 1]])
        outcomes.append(Outcome(float(ends[k]), positions, log, {}))
    return outcomes


Batch = tuple[list[tuple[list[int], np.ndarray, np.ndarray]], np.ndarray, np.ndarray, np.ndarray]


def run_batch(scenes: Sequence[Scene], horizons: Sequence[float] | None, max_events: int) -> Batch:
    """The kernel's raw batch results: per-scene ``(ids, pos, vel)`` (``pos`` and ``vel`` left
    empty: the flat arrays went to the kernel), ball offsets, final rows and the event rows
    (scene index first) of ``scenes`` (sharing one table)."""
    first = scenes[0]
    shape = (first.table, first.physics, first.pockets)
    if any(
        (s.table, s.physics, s.pockets) != shape
        for s in scenes
        if s.table is not first.table or s.physics is not first.physics
        or s.pockets is not first.pockets
    ):  # fmt: skip
        raise ValueError("simulate_many: scenes must share table, physics and pockets")
    ordered = [sorted(s.balls, key=_ball_id) for s in scenes]
    pos = np.array([b.pos for balls in ordered for b in balls], dtype=float).reshape(-1, 2)
    vel = np.array([b.vel for balls in ordered for b in balls], dtype=float).reshape(-1, 2)
    starts = np.cumsum([0] + [len(balls) for balls in ordered])
    ends = [s.horizon for s in scenes] if horizons is None else list(horizons)
    prm, pockets = table_params(first)
    final, status, events = run_many_arrays(
        pos, vel, starts, prm, pockets, np.array(ends, dtype=float), max_events
    )
    if status.any():
        raise KernelBudgetError(f"scene {int(np.argmax(status))}: more than {max_events} events")
    empty = np.zeros((0, 2))
    arrays = [([b.id for b in balls], empty, empty) for balls in ordered]
    return arrays, starts, final, events


def _ball_id(ball: Any) -> int:
    return int(ball.id)


def _batch(
    arrays: list[tuple[list[int], np.ndarray, np.ndarray]],
    starts: np.ndarray,
    final: np.ndarray,
    events: np.ndarray,
) -> BatchResult:
    rows = final.tolist()
    positions = [
        {i: (r[0], r[1]) if r[2] else None for i, r in zip(ids, rows[a:b], strict=True)}
        for (ids, _, _), a, b in zip(arrays, starts[:-1].tolist(), starts[1:].tolist(), strict=True)
    ]
    contacts: list[set[int]] = [set() for _ in arrays]
    walls: list[set[str]] = [set() for _ in arrays]
    counts = np.bincount(events[:, 0].astype(np.int64), minlength=len(arrays)).tolist()
    kind, a, b = events[:, 2], events[:, 3], events[:, 4]
    cue_rows = ((kind == 0) | (kind == 1)) & ((a == 0) | (b == 0))  # index 0: the lowest id
    for s, _, kind_, a_, b_, wall, *_ in events[cue_rows].tolist():
        ids = arrays[int(s)][0]
        if kind_ == 0 and (ids[int(a_)] == 0 or ids[int(b_)] == 0):
            contacts[int(s)].add(ids[int(b_)] if ids[int(a_)] == 0 else ids[int(a_)])
        elif kind_ == 1 and ids[int(a_)] == 0:
            walls[int(s)].add(WALLS[int(wall)])
    return BatchResult(positions, contacts, walls, counts)
