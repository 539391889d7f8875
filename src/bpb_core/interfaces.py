"""The interfaces plugins implement: Task, SceneFamily, Simulator, ModelAdapter and Scorer.

They are :class:`typing.Protocol` classes: a plugin need not inherit from them, only provide the
attributes and methods.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, Protocol, runtime_checkable

if TYPE_CHECKING:
    import random

    from bpb_core.adapters import Message, ModelRequest, ModelResponse
    from bpb_core.outcome import Outcome
    from bpb_core.scene import FinalState, Scene

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
    """Scores one task's answers against ground truth.

    Attributes:
        task: Name of the task it scores.
    """

    name: str
    task: str

    def score(
        self, answer: Mapping[str, Any] | None, final: FinalState, scene: Scene
    ) -> Sequence[Mapping[str, Any]]:
        """Rows of scored units (one per ball or per scene) for one answer; ``None`` = missing."""
        ...
