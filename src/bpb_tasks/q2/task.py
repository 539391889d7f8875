"""Q2: for each wall, did the cue ball touch it in [0, t]? Answers ``T``/``F``."""

from __future__ import annotations

from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict, field_validator

from bpb_core.errors import ParseFailure
from bpb_core.interfaces import PromptOptions
from bpb_tasks.billiards.scene.model import WALLS, Scene, Wall
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.questions.answers import TF, Item, Q2Schema, load, upper
from bpb_tasks.questions.question import LabelQuestion


class WallAnswer(Item):
    """Q2 item: did the cue ball touch ``wall``."""

    wall: Wall
    answer: TF

    @field_validator("wall", "answer", mode="before")
    @classmethod
    def _upper(cls, value: Any) -> Any:
        return upper(value)


class Q2Answer(BaseModel):
    """``{"answers": [{"wall": "TOP", "answer": "F"}, ...]}``."""

    model_config = ConfigDict(extra="ignore", frozen=True)
    answers: list[WallAnswer]


class Q2Task(LabelQuestion):
    """Cue-ball contacts with each wall (chain of thought on by default)."""

    name: ClassVar[str] = "q2"
    default_cot: ClassVar[bool] = True
    title: ClassVar[str] = "Wall contacts"
    key: ClassVar[str] = "wall"
    schema = Q2Schema

    def units(self, scene: Scene) -> list[Wall]:
        """The walls: TOP, BOTTOM, LEFT, RIGHT."""
        return list(WALLS)

    def question(self, scene: Scene, options: PromptOptions) -> str:
        return (
            f"For each wall TOP, BOTTOM, LEFT and RIGHT, does the cue ball (ball 0) touch it at "
            f"any time in [0, {scene.horizon:g}] s? Answer T (yes) or F (no) for all four walls, "
            f"as JSON:\n{self.example(scene)}"
        )

    def validate(self, value: Any, scene: Scene) -> dict[str, Any]:
        """Validate a Q2 answer: one T/F per wall, in TOP, BOTTOM, LEFT, RIGHT order."""
        answer = load(Q2Answer, "q2", value)
        walls = [a.wall for a in answer.answers]
        if len(walls) != len(set(walls)) or set(walls) != set(WALLS):
            raise ParseFailure(f"q2: walls must be {list(WALLS)} once each, got {walls}")
        by_wall = {a.wall: a.answer for a in answer.answers}
        return {"answers": [{"wall": w, "answer": by_wall[w]} for w in WALLS]}

    def expected(self, truth: FinalState) -> dict[str, Any]:
        return {"answers": [label.model_dump() for label in truth.q2]}

    def form_context(self, scene: Scene, image: bytes | None) -> dict[str, Any]:
        """The walls to tick (``bpb human``)."""
        return {"horizon": f"{scene.horizon:g}", "walls": list(WALLS)}
