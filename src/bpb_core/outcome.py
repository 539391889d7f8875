"""What a simulator returns, and the ground truth derived from it.

An :class:`Outcome` is plain frozen data: the state at the horizon, every event up to it, and
the piecewise motion of every ball (for rendering). :func:`final_state` turns it into the
``final.json`` model.
"""

from __future__ import annotations

from dataclasses import dataclass

from bpb_core.scene import WALLS, BallPosition, EventRecord, FinalState, Q1Label, Q2Label, Scene

CUE_ID = 0


@dataclass(frozen=True)
class Event:
    """An event at time ``t``; ``kind`` is ball, wall, pocket or stop."""

    t: float
    kind: str
    ids: tuple[int, ...]
    wall: str | None = None
    positions: tuple[tuple[float, float], ...] = ()


@dataclass(frozen=True)
class Segment:
    """A stretch of motion of one ball under constant deceleration ``decel`` along ``vel``.

    The ball is at ``pos`` with velocity ``vel`` at ``t0`` and follows this law until ``t1``.
    """

    t0: float
    t1: float
    pos: tuple[float, float]
    vel: tuple[float, float]
    decel: float


@dataclass(frozen=True)
class Outcome:
    """A simulated scene at ``horizon``.

    Attributes:
        positions: Ball id to centre at the horizon, ``None`` if pocketed by then.
        events: Ball-ball, wall, pocket and stop events in [0, horizon], in processing order.
        segments: Ball id to its motion pieces covering [0, horizon] (or until pocketed).
    """

    horizon: float
    positions: dict[int, tuple[float, float] | None]
    events: tuple[Event, ...]
    segments: dict[int, tuple[Segment, ...]]

    def cue_contacts(self) -> set[int]:
        """Ids of the balls the cue ball touched."""
        hits: set[int] = set()
        for event in self.events:
            if event.kind == "ball" and CUE_ID in event.ids:
                hits.update(i for i in event.ids if i != CUE_ID)
        return hits

    def cue_walls(self) -> set[str]:
        """Walls the cue ball touched."""
        return {e.wall for e in self.events if e.kind == "wall" and e.ids == (CUE_ID,) and e.wall}


def final_state(scene: Scene, outcome: Outcome, simulator: str = "analytic") -> FinalState:
    """Ground truth of ``scene`` from its simulated ``outcome`` (positions rounded to 4 dp)."""
    contacts, walls = outcome.cue_contacts(), outcome.cue_walls()
    object_ids = sorted(b.id for b in scene.balls if b.id != CUE_ID)

    def rounded(pos: tuple[float, float] | None) -> tuple[float, float] | None:
        return None if pos is None else (round(pos[0], 4) + 0.0, round(pos[1], 4) + 0.0)

    return FinalState(
        scene_id=scene.scene_id,
        horizon=outcome.horizon,
        q1=[Q1Label(id=i, answer="T" if i in contacts else "F") for i in object_ids],
        q2=[Q2Label(wall=w, answer="T" if w in walls else "F") for w in WALLS],
        predictions=[
            BallPosition(id=b.id, pos=rounded(outcome.positions[b.id]))
            for b in sorted(scene.balls, key=lambda b: b.id)
        ],
        events=[
            EventRecord(
                t=e.t, kind=e.kind, ids=list(e.ids), wall=e.wall, positions=list(e.positions)
            )
            for e in outcome.events
        ],
        simulator=simulator,
    )
