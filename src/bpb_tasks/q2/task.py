"""Q2: for each wall, did the cue ball touch it in [0, t]? Answers ``T``/``F``."""

from __future__ import annotations

from typing import Annotated, Any, ClassVar

from bpb_core.errors import ParseFailure
from bpb_tasks.billiards.scene.model import WALLS, Scene, Wall
from bpb_tasks.questions.answers import TF, Answers, Item, Q2Schema, Upper
from bpb_tasks.questions.question import LabelQuestion


class WallAnswer(Item):
    """Q2 item: did the cue ball touch ``wall``."""

    wall: Annotated[Wall, Upper]
    answer: Annotated[TF, Upper]


class Q2Task(LabelQuestion):
    """Cue-ball contacts with each wall (chain of thought on by default)."""

    name: ClassVar[str] = "q2"
    title: ClassVar[str] = "Wall contacts"
    key: ClassVar[str] = "wall"
    reader = Answers[WallAnswer]
    schema = Q2Schema

    def units(self, scene: Scene) -> list[Wall]:
        """The walls: TOP, BOTTOM, LEFT, RIGHT."""
        return list(WALLS)

    def asked(self, scene: Scene) -> tuple[str, str]:
        return "wall TOP, BOTTOM, LEFT and RIGHT", "all four walls"

    def check(self, got: list[Any], units: list[Any]) -> None:
        if len(got) != len(set(got)) or set(got) != set(WALLS):
            raise ParseFailure(f"q2: walls must be {list(WALLS)} once each, got {got}")

    def form_context(self, scene: Scene, image: bytes | None) -> dict[str, Any]:
        """The walls to tick (``bpb human``)."""
        return {"horizon": f"{scene.horizon:g}", "walls": list(WALLS)}
