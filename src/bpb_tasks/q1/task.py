"""Q1: for each object ball, did the cue ball touch it in [0, t]? Answers ``T``/``F``."""

from __future__ import annotations

import json
from typing import Any, ClassVar

from bpb_core.interfaces import PromptOptions
from bpb_core.scene import FinalState, Scene
from bpb_tasks.answers import validate_q1
from bpb_tasks.prompting_task import BuiltinTask


class Q1Task(BuiltinTask):
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

    def expected(self, final: FinalState) -> dict[str, Any]:
        return {"answers": [label.model_dump() for label in final.q1]}
