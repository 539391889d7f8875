"""Q1: for each object ball, did the cue ball touch it in [0, t]? Answers ``T``/``F``."""

from __future__ import annotations

from typing import Annotated, Any, ClassVar

from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.questions.answers import TF, Answers, BallId, Item, Q1Schema, Upper
from bpb_tasks.questions.question import LabelQuestion, colour


class BallAnswer(Item):
    """Q1 item: did the cue ball touch ball ``id``."""

    id: BallId
    answer: Annotated[TF, Upper]


class Q1Task(LabelQuestion):
    """Cue-ball collisions with each object ball (chain of thought on by default)."""

    name: ClassVar[str] = "q1"
    title: ClassVar[str] = "Ball collisions"
    key: ClassVar[str] = "id"
    reader = Answers[BallAnswer]
    schema = Q1Schema

    def units(self, scene: Scene) -> list[int]:
        """The object balls' ids, in order."""
        return sorted(b.id for b in scene.balls if b.id != 0)

    def field(self, unit: Any) -> str:
        return f"ball{unit}"

    def asked(self, scene: Scene) -> tuple[str, str]:
        return f"object ball {self.units(scene)}", "every one of them"

    def form_context(self, scene: Scene, image: bytes | None) -> dict[str, Any]:
        """The object balls to tick (``bpb human``)."""
        balls = [{"id": i, "colour": colour(i)} for i in self.units(scene)]
        return {"horizon": f"{scene.horizon:g}", "balls": balls}
