"""What a billiards simulator returns.

An :class:`Outcome` is plain frozen data: the state at the horizon, every event up to it, and
the piecewise motion of every ball (for rendering).
:func:`bpb_tasks.billiards.truth.final.final_state` turns it into the ``final.json`` model.
"""

from __future__ import annotations

from dataclasses import dataclass

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
