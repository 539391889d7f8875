"""Q1: for each object ball, did the cue ball touch it in [0, t]? Answers ``T``/``F``."""

from __future__ import annotations

from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict, field_validator

from bpb_core.interfaces import PromptOptions
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.questions.answers import TF, Item, Q1Schema, check_ids, load, read_id, upper
from bpb_tasks.questions.browser import colour
from bpb_tasks.questions.question import LabelQuestion


class BallAnswer(Item):
    """Q1 item: did the cue ball touch ball ``id``."""

    id: int
    answer: TF

    @field_validator("id", mode="before")
    @classmethod
    def _id(cls, value: Any) -> int:
        return read_id(value)

    @field_validator("answer", mode="before")
    @classmethod
    def _tf(cls, value: Any) -> Any:
        return upper(value)


class Q1Answer(BaseModel):
    """``{"answers": [{"id": 1, "answer": "T"}, ...]}``."""

    model_config = ConfigDict(extra="ignore", frozen=True)
    answers: list[BallAnswer]


class Q1Task(LabelQuestion):
    """Cue-ball collisions with each object ball (chain of thought on by default)."""

    name: ClassVar[str] = "q1"
    default_cot: ClassVar[bool] = True
    title: ClassVar[str] = "Ball collisions"
    key: ClassVar[str] = "id"
    schema = Q1Schema

    def units(self, scene: Scene) -> list[int]:
        """The object balls' ids, in order."""
        return sorted(b.id for b in scene.balls if b.id != 0)

    def field(self, unit: Any) -> str:
        return f"ball{unit}"

    def question(self, scene: Scene, options: PromptOptions) -> str:
        return (
            f"For each object ball {self.units(scene)}, does the cue ball (ball 0) touch it at any "
            f"time in [0, {scene.horizon:g}] s? Answer T (yes) or F (no) for every one of them, as "
            f"JSON:\n{self.example(scene)}"
        )

    def validate(self, value: Any, scene: Scene) -> dict[str, Any]:
        """Validate a Q1 answer: one T/F per object ball, in id order."""
        answer = load(Q1Answer, "q1", value)
        check_ids("q1", [a.id for a in answer.answers], self.units(scene))
        items = sorted(answer.answers, key=lambda a: a.id)
        return {"answers": [{"id": a.id, "answer": a.answer} for a in items]}

    def expected(self, truth: FinalState) -> dict[str, Any]:
        return {"answers": [label.model_dump() for label in truth.q1]}

    def form_context(self, scene: Scene, image: bytes | None) -> dict[str, Any]:
        """The object balls to tick (``bpb human``)."""
        balls = [{"id": i, "colour": colour(i)} for i in self.units(scene)]
        return {"horizon": f"{scene.horizon:g}", "balls": balls}
