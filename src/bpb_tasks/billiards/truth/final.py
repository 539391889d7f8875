"""The billiards ground truth: the model of ``final.json`` (SPEC section 4), and how it is
derived from a simulated :class:`~bpb_tasks.billiards.truth.outcome.Outcome`.

``q1`` and ``q2`` hold the cue ball's contacts with each object ball and each wall, ``predictions``
every ball's position at the horizon, ``events`` the full event log and ``stability`` how close
those labels are to flipping. :func:`final_json_schema` publishes the model as a JSON Schema.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from bpb_tasks.billiards.scene.model import WALLS, Scene, StrictModel, Vec, Wall
from bpb_tasks.billiards.truth.outcome import CUE_ID, Outcome

TF = Literal["T", "F"]


class Q1Label(StrictModel):
    """Did the cue ball touch object ball ``id``?"""

    id: int
    answer: TF


class Q2Label(StrictModel):
    """Did the cue ball touch ``wall``?"""

    wall: Wall
    answer: TF


class BallPosition(StrictModel):
    """A ball's centre at the horizon; ``None`` once pocketed."""

    id: int
    pos: Vec | None


EventKind = Literal["ball", "wall", "pocket", "stop"]


class EventRecord(StrictModel):
    """One event: ``ids`` are the balls involved, ``positions`` their centres at time ``t``."""

    t: float
    kind: EventKind
    ids: list[int]
    wall: Wall | None = None
    positions: list[Vec] = Field(default_factory=list)


UNFINISHED = "unfinished"
"""The name in :attr:`Stability.flips` (and :attr:`FinalState.unstable_reasons`) of perturbed
copies the simulator could not finish within their event budget."""


OVERLAP = "overlap"
"""The name in :attr:`FinalState.unstable_reasons` of a nominal run in which two balls overlap
(:attr:`Stability.overlap`)."""


class Stability(BaseModel):
    """How likely the scene's labels are to flip (SPEC section 3;
    :mod:`bpb_tasks.billiards.stability` defines the perturbations).

    Attributes:
        stable: No label flipped in any of ``samples`` perturbations, the Q3 spread is at most
            half a ball radius and ``overlap`` is null (the other margins do not count).
        delta: Perturbation size: metres for positions, a share of the cue speed for velocity.
        samples: Number of random perturbations.
        flip_rates: Share of perturbations flipping a Q1, a Q2 or a pocketed label.
        flip_rate: Share of perturbations flipping any label.
        flip_rate_upper95: Exact upper 95% bound on the probability that a perturbation flips
            any label (about ``3 / samples`` when none flipped).
        q3_spread: Largest distance (m) between a ball's perturbed and nominal final positions.
        q3_stable: ``q3_spread`` is at most half a ball radius.
        near_miss_gap: Smallest gap (m) between balls that did not touch (negative when they
            overlap, a collision the simulator missed; then ``overlap`` holds it too).
        min_graze_cos: Smallest |cos| of the approach angle over contacts (grazing near 0).
        min_event_gap: Smallest time (s) between two events sharing a ball.
        horizon_gap: Time (s) between the horizon and the nearest event, looking up to 1 s
            past the horizon; null when there is none. The run past the horizon stops at the
            simulator's event cap (pymunk's: where its run would fail, a ball through a
            cushion or its step budget) instead of failing the scene: the gap is still exact
            when an event after the horizon came before the cap (almost always), and null (not
            measured) when only stops did and the nearest event before the horizon is
            farther than the last of them.
        pocket_gap: Nearest pocket-edge pass (m): closest distance of a moving centre to a pocket
            it does not enter, minus the pocket radius.
        overlap: Deepest overlap (m) of two balls in the nominal run, ``2R`` minus their closest
            distance, when over the contact tolerance of 1e-9 m: balls in a pressing contact,
            which the event model does not resolve (the dataset card's known limitation).
            Null when there is none, and for a simulator that steps time (pymunk), whose
            balls overlap at every contact.
        flips: Labels that flipped under perturbation, e.g. ``q1:3``, ``q2:TOP``, ``q3:pocket:5``,
            and ``unfinished`` when the simulator could not finish some perturbed copy within
            its event budget (balls chattering in a pressing contact). Such a copy counts in
            ``flip_rate``, in no group of ``flip_rates`` and not in ``q3_spread``.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)

    stable: bool
    delta: float
    samples: int = 0
    flip_rates: dict[str, float] = Field(default_factory=dict)
    flip_rate: float = 0.0
    flip_rate_upper95: float = 1.0
    q3_spread: float = 0.0
    q3_stable: bool = True
    near_miss_gap: float | None = None
    min_graze_cos: float | None = None
    min_event_gap: float | None = None
    horizon_gap: float | None = None
    pocket_gap: float | None = None
    overlap: float | None = None
    flips: list[str] = Field(default_factory=list)


class FinalState(StrictModel):
    """Ground truth at the horizon: the content of ``final.json``."""

    scene_id: str
    horizon: float
    q1: list[Q1Label]
    q2: list[Q2Label]
    predictions: list[BallPosition]
    events: list[EventRecord] = Field(default_factory=list)
    stability: Stability | None = None
    simulator: str = "analytic"

    @property
    def stable(self) -> bool | None:
        """Whether no label flips under the stability perturbations (``None``: not annotated)."""
        return None if self.stability is None else self.stability.stable

    @property
    def unstable_reasons(self) -> list[str]:
        """The stability conditions the scene fails: ``q1``, ``q2``, ``pocketed`` (a label of
        that kind flipped), ``q3`` (Q3 spread over half a ball radius), ``overlap`` (two balls
        overlap in the nominal run) and ``unfinished`` (a perturbed copy ran past its event
        budget); empty when stable or not annotated."""
        s = self.stability
        if s is None:
            return []
        flipped = [g for g in ("q1", "q2", "pocketed") if s.flip_rates.get(g, 0.0) > 0]
        unfinished = [UNFINISHED] if UNFINISHED in s.flips else []
        overlap = [] if s.overlap is None else [OVERLAP]
        return flipped + ([] if s.q3_stable else ["q3"]) + overlap + unfinished


def final_json_schema() -> dict[str, Any]:
    """JSON Schema of ``final.json``."""
    return FinalState.model_json_schema()


def final_state(scene: Scene, outcome: Outcome, simulator: str = "analytic") -> FinalState:
    """Ground truth of ``scene`` from its simulated ``outcome`` (positions rounded to 4 dp)."""
    contacts, walls = outcome.cue_contacts(), outcome.cue_walls()
    object_ids = sorted(b.id for b in scene.balls if b.id != CUE_ID)

    def rounded(pos: tuple[float, float] | None) -> tuple[float, float] | None:
        return None if pos is None else (round(pos[0], 4) + 0.0, round(pos[1], 4) + 0.0)

    # one validation of plain values (the model checks the simulator's kinds and wall names)
    return FinalState.model_validate(
        {
            "scene_id": scene.scene_id,
            "horizon": outcome.horizon,
            "q1": [{"id": i, "answer": "T" if i in contacts else "F"} for i in object_ids],
            "q2": [{"wall": w, "answer": "T" if w in walls else "F"} for w in WALLS],
            "predictions": [
                {"id": b.id, "pos": rounded(outcome.positions[b.id])}
                for b in sorted(scene.balls, key=lambda b: b.id)
            ],
            "events": [
                {
                    "t": e.t,
                    "kind": e.kind,
                    "ids": list(e.ids),
                    "wall": e.wall,
                    "positions": list(e.positions),
                }
                for e in outcome.events
            ],
            "simulator": simulator,
        }
    )
