"""Q1: for each object ball, did the cue ball touch it in [0, t]? Answers ``T``/``F``."""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict, field_validator

from bpb_core.interfaces import PromptOptions
from bpb_tasks.billiards.scene import Scene
from bpb_tasks.billiards.truth import FinalState
from bpb_tasks.questions.answers import TF, Item, check_ids, load, read_id, upper
from bpb_tasks.questions.browser import colour, read_ticks
from bpb_tasks.questions.question import BilliardsQuestion
from bpb_tasks.questions.schemas import Q1Schema, schema_of


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


def validate_q1(value: Any, scene: Scene) -> dict[str, Any]:
    """Validate a Q1 answer: one T/F per object ball, in id order."""
    answer = load(Q1Answer, "q1", value)
    object_ids = [b.id for b in scene.balls if b.id != 0]
    check_ids("q1", [a.id for a in answer.answers], object_ids)
    items = sorted(answer.answers, key=lambda a: a.id)
    return {"answers": [{"id": a.id, "answer": a.answer} for a in items]}


class Q1Task(BilliardsQuestion):
    """Cue-ball collisions with each object ball (chain of thought on by default)."""

    name: ClassVar[str] = "q1"
    default_cot: ClassVar[bool] = True
    title: ClassVar[str] = "Ball collisions"

    def example(self, scene: Scene) -> str:
        ids = sorted(b.id for b in scene.balls if b.id != 0)
        items = [{"id": i, "answer": "T" if n == 0 else "F"} for n, i in enumerate(ids)]
        return json.dumps({"answers": items})

    def question(self, scene: Scene, options: PromptOptions) -> str:
        ids = sorted(b.id for b in scene.balls if b.id != 0)
        return (
            f"For each object ball {ids}, does the cue ball (ball 0) touch it at any time in "
            f"[0, {scene.horizon:g}] s? Answer T (yes) or F (no) for every one of them, as JSON:\n"
            f"{self.example(scene)}"
        )

    def validate(self, value: Any, scene: Scene) -> dict[str, Any]:
        return validate_q1(value, scene)

    def expected(self, truth: FinalState) -> dict[str, Any]:
        return {"answers": [label.model_dump() for label in truth.q1]}

    def form_context(self, scene: Scene, image: bytes | None) -> dict[str, Any]:
        """The object balls to tick (``bpb human``)."""
        ids = sorted(b.id for b in scene.balls if b.id != 0)
        balls = [{"id": i, "colour": colour(i)} for i in ids]
        return {"horizon": f"{scene.horizon:g}", "balls": balls}

    def read_form(self, fields: Mapping[str, str], scene: Scene) -> dict[str, Any]:
        """Ticked balls ``ball<id>`` are ``T``, the others ``F``."""
        ids = sorted(b.id for b in scene.balls if b.id != 0)
        ticked = read_ticks(fields, [f"ball{i}" for i in ids])
        return {"answers": [{"id": i, "answer": "T" if f"ball{i}" in ticked else "F"} for i in ids]}

    def answer_schema(self) -> dict[str, Any]:
        """The JSON Schema of the normalised answer (``docs/schemas/q1.answer.schema.json``)."""
        return schema_of(Q1Schema, self.name)
