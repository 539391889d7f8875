"""The interfaces plugins implement: Task, SceneFamily, Simulator, ModelAdapter and Scorer.

They are :class:`typing.Protocol` classes: a plugin need not inherit from them, only provide the
attributes and methods.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, Protocol, runtime_checkable

if TYPE_CHECKING:
    import random

    import pandas as pd

    from bpb_core.adapters import Message, ModelRequest, ModelResponse
    from bpb_core.outcome import Outcome
    from bpb_core.scene import FinalState, Scene
    from bpb_core.units import UnitRow

InputMode = Literal["image", "image+state", "state"]


@dataclass(frozen=True)
class PromptOptions:
    """How a prompt is built.

    Attributes:
        input_mode: ``image`` (the paper), ``image+state`` or ``state`` (text only).
        cot: Ask for reasoning before the JSON answer.
        force_numeric: Ask for numeric positions instead of ``null``.
        escalation: 0 on the first ask; higher on re-asks after a malformed answer.
    """

    input_mode: InputMode = "image"
    cot: bool = False
    force_numeric: bool = False
    escalation: int = 0


@dataclass(frozen=True)
class ParsedAnswer:
    """A validated answer in the task's answer format, and which extraction rule found it."""

    value: dict[str, Any]
    rule: str


@runtime_checkable
class Task(Protocol):
    """A question about a scene.

    Attributes:
        name: Short name (``q1``).
        default_cot: Whether chain of thought is on by default.
    """

    name: str
    default_cot: bool

    def messages(
        self, scene: Scene, image: bytes | None, options: PromptOptions
    ) -> tuple[Message, ...]:
        """Build the prompt from the scene alone (never from ground truth)."""
        ...

    def parse(self, text: str, scene: Scene, options: PromptOptions) -> ParsedAnswer:
        """Extract and validate the answer; raise :class:`~bpb_core.errors.ParseFailure`."""
        ...

    def expected(self, final: FinalState) -> dict[str, Any]:
        """The correct answer, in the task's answer format, from the ground truth."""
        ...


@runtime_checkable
class Simulator(Protocol):
    """A physics engine."""

    name: str

    def run(self, scene: Scene, horizon: float | None = None) -> Outcome:
        """Simulate ``scene`` to ``horizon`` (default: the scene's own horizon)."""
        ...


@runtime_checkable
class SceneFamily(Protocol):
    """A generator of scenes of one kind."""

    name: str

    def sample(
        self, rng: random.Random, horizon: float, index: int, config: Mapping[str, Any]
    ) -> Scene:
        """Draw one scene from ``rng`` (seeded from seed, horizon and index)."""
        ...


@runtime_checkable
class ModelAdapter(Protocol):
    """Talks to one model. Raises :mod:`bpb_core.errors` model errors on failure."""

    name: str

    async def complete(self, request: ModelRequest) -> ModelResponse:
        """Send one request and return the reply."""
        ...


@runtime_checkable
class Scorer(Protocol):
    """Scores one task's answers against ground truth, in two steps.

    1. :meth:`units` cuts one answer into scored units (:class:`~bpb_core.units.UnitRow`: one
       per object ball, wall or ball position), pairing each with its true label. It is called
       once per (run, scene, task) while :func:`bpb_core.results.load_frame` reads the files.
    2. :meth:`score` marks a whole frame of units at once, vectorised: it must score one
       million rows in well under two seconds. Its input has the columns of
       :data:`bpb_core.units.SCORER_INPUT`; it returns a frame with the same index and the
       columns ``correct`` (bool) and ``distance`` (float64, NaN when not a position task).

    A unit can only be correct when the call's ``status`` is ``ok``. Units the answer does not
    mention, and units it mentions more than once (duplicate ids), are wrong; entries naming
    units the truth does not have, and extra keys inside entries, are ignored.

    Attributes:
        name: Scorer name (``q1``).
        task: Name of the task it scores.
        scene_rule: How unit results make a scene's score: ``mean`` (share of correct units,
            Q1 and Q3) or ``all`` (1 only when every unit is correct, Q2's exact set match).
    """

    name: str
    task: str
    scene_rule: Literal["mean", "all"]

    def units(
        self, answer: Mapping[str, Any] | None, final: FinalState, scene: Scene
    ) -> list[UnitRow]:
        """The scored units of one answer (``None`` = no answer), in a fixed order."""
        ...

    def score(self, units: pd.DataFrame) -> pd.DataFrame:
        """Columns ``correct`` and ``distance`` for every row of ``units``."""
        ...
