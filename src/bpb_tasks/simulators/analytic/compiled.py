"""Scenes in, outcomes out: the Python side of the compiled event kernel.

:func:`kernel_outcome` simulates one :class:`~bpb_tasks.billiards.scene.model.Scene` with
:func:`~bpb_tasks.simulators.analytic.kernel.run_arrays` and builds the same
:class:`~bpb_tasks.billiards.truth.outcome.Outcome` the reference engine does. :func:`outcomes_many`
is the batch API behind ``AnalyticSimulator.run_many``: many scenes in one compiled call, their
outcomes without motion pieces; the stability copies take :func:`run_batch`'s arrays.
:func:`kernel_failure` loads (or builds) the kernel's entry points, or says why numba could not.
"""

from __future__ import annotations

from collections.abc import Sequence
from operator import attrgetter

import numpy as np

from bpb_tasks.billiards.scene.model import WALLS, Ball, Scene
from bpb_tasks.billiards.truth.outcome import Event, Outcome, Segment
from bpb_tasks.simulators.analytic.engine import KIND_NAMES, SimulationError
from bpb_tasks.simulators.analytic.kernel import HAVE_NUMBA, run_arrays, run_many_arrays


def table_params(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's table constants (``kernel``'s :data:`DECEL` .. :data:`POCKET_R`,
    the same arithmetic as the reference ``Predictor``) and pocket centres of ``scene``."""
    table, phys, pockets = scene.table, scene.physics, scene.pockets
    radius = phys.ball_radius
    decel = phys.mu * phys.g
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
            pockets.radius,
        ]
    )
    return prm, np.array(pockets.centers, dtype=float).reshape(-1, 2)


def scene_arrays(scene: Scene) -> tuple[list[int], np.ndarray, np.ndarray]:
    """Ball ids (sorted), positions and velocities of ``scene``."""
    balls = sorted(scene.balls, key=attrgetter("id"))
    pos = np.array([b.pos for b in balls], dtype=float).reshape(-1, 2)
    vel = np.array([b.vel for b in balls], dtype=float).reshape(-1, 2)
    return [b.id for b in balls], pos, vel


def kernel_failure(scene: Scene) -> str | None:
    """Load (or build) the kernel's entry points by running a ball at rest on ``scene``'s table
    through each as the real calls do: ``None`` when they run, else what went wrong (numba
    cannot read a cache file of them, say); numba keeps what it loaded, so the calls after this
    one take it."""
    from bpb_tasks.billiards.stability.annotation import perturbation_arrays
    from bpb_tasks.billiards.stability.kernel import copy_labels

    if not HAVE_NUMBA:
        return "numba could not be imported"
    table = scene.table  # one ball at rest mid-table: one event at most
    still = Ball.model_construct(id=0, pos=(table.width / 2, table.height / 2), vel=(0.0, 0.0))
    one = scene.model_copy(update={"balls": [still]})
    try:
        kernel_outcome(one, one.horizon, 10_000)
        run_batch([one], None, 10_000, check=False)
        ids, pos, vel = perturbation_arrays(one, 1e-4, 1)
        copy_labels(one, ids, pos, vel, 10_000)
    except Exception as exc:  # whatever numba raised: the kernel is not to be used
        return f"{type(exc).__name__}: {exc}"
    return None


def kernel_outcome(scene: Scene, horizon: float, max_events: int) -> Outcome:
    """Simulate ``scene`` to ``horizon`` with the kernel; the reference engine's Outcome."""
    ids, pos, vel = scene_arrays(scene)
    prm, pockets = table_params(scene)
    events, pieces, final, status = run_arrays(pos, vel, prm, pockets, float(horizon), max_events)
    if status:
        raise SimulationError(f"more than {max_events} events before t={float(horizon)}")
    decel = float(prm[0])
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
    return Outcome(float(horizon), positions, _event_log(ids, events.tolist()), segments)


def _event_log(ids: Sequence[int], rows: list[list[float]]) -> tuple[Event, ...]:
    """The events of the kernel's event rows ``(t, kind, a, b, wall, xa, ya, xb, yb)``, whose
    balls ``a`` and ``b`` are indices into ``ids``."""
    log = []
    for t, kind, a, b, wall, xa, ya, xb, yb in rows:
        if b >= 0:
            log.append(Event(t, "ball", (ids[int(a)], ids[int(b)]), None, ((xa, ya), (xb, yb))))
        else:
            name = WALLS[int(wall)] if wall >= 0 else None
            log.append(Event(t, KIND_NAMES[int(kind)], (ids[int(a)],), name, ((xa, ya),)))
    return tuple(log)


def outcomes_many(
    scenes: Sequence[Scene], horizons: Sequence[float] | None = None, max_events: int = 100_000
) -> list[Outcome]:
    """The outcomes of many scenes (sharing table, physics and pockets) run to ``horizons``
    (default: their own) in one compiled call: final positions and events, and no motion
    pieces (``segments`` empty: nothing to draw from them).

    Raises:
        ValueError: The scenes do not share one table.
        SimulationError: A scene exceeded ``max_events``.
    """
    if not scenes:
        return []
    ends = [s.horizon for s in scenes] if horizons is None else list(horizons)
    ids, starts, final, _, events = run_batch(scenes, ends, max_events)
    rows = final.tolist()
    bounds = np.searchsorted(events[:, 0], np.arange(len(scenes) + 1)).tolist()  # in scene order
    event_rows = events[:, 1:].tolist()
    outcomes = []
    for k, (own, a, b) in enumerate(
        zip(ids, starts[:-1].tolist(), starts[1:].tolist(), strict=True)
    ):
        positions = {i: (r[0], r[1]) if r[2] else None for i, r in zip(own, rows[a:b], strict=True)}
        log = _event_log(own, event_rows[bounds[k] : bounds[k + 1]])
        outcomes.append(Outcome(float(ends[k]), positions, log, {}))
    return outcomes


def run_batch(
    scenes: Sequence[Scene], horizons: Sequence[float] | None, max_events: int, check: bool = True
) -> tuple[list[list[int]], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The kernel's raw batch results of ``scenes`` (sharing one table) run to ``horizons``
    (default: their own): per-scene ball ids, ball offsets, final rows, statuses and the event
    rows (scene index first).

    Raises:
        SimulationError: A scene exceeded ``max_events`` (when ``check``).
    """
    first = scenes[0]
    shape = (first.table, first.physics, first.pockets)
    if any(
        (s.table, s.physics, s.pockets) != shape
        for s in scenes
        if s.table is not first.table or s.physics is not first.physics
        or s.pockets is not first.pockets
    ):  # fmt: skip
        raise ValueError("outcomes_many: scenes must share table, physics and pockets")
    ordered = [sorted(s.balls, key=attrgetter("id")) for s in scenes]
    pos = np.array([b.pos for balls in ordered for b in balls], dtype=float).reshape(-1, 2)
    vel = np.array([b.vel for balls in ordered for b in balls], dtype=float).reshape(-1, 2)
    starts = np.cumsum([0] + [len(balls) for balls in ordered])
    ends = [s.horizon for s in scenes] if horizons is None else list(horizons)
    prm, pockets = table_params(first)
    final, status, events = run_many_arrays(
        pos, vel, starts, prm, pockets, np.array(ends, dtype=float), max_events
    )
    if check and status.any():
        raise SimulationError(f"scene {int(np.argmax(status))}: more than {max_events} events")
    return [[b.id for b in balls] for balls in ordered], starts, final, status, events
