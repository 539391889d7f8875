"""Q2: for each wall, did the cue ball touch it in [0, t]? Answers ``T``/``F``."""

from __future__ import annotations

import json
from typing import Any, ClassVar

from bpb_core.interfaces import PromptOptions
from bpb_core.scene import WALLS, FinalState, Scene
from bpb_tasks.answers import validate_q2
from bpb_tasks.prompting_task import BuiltinTask


class Q2Task(BuiltinTask):
    """Cue-ball contacts with each wall (chain of thought on by default)."""

    name: ClassVar[str] = "q2"
    default_cot: ClassVar[bool] = True
    title: ClassVar[str] = "Wall contacts"

    def example(self, scene: Scene) -> str:
        items = [{"wall": w, "answer": "T" if w == "TOP" else "F"} for w in WALLS]
        return json.dumps({"answers": items})

    def question(self, scene: Scene, options: PromptOptions) -> str:
        return (
            f"For each wall TOP, BOTTOM, LEFT and RIGHT, does the cue ball (ball 0) touch it at "
            f"any time in [0, {scene.horizon:g}] s? Answer T (yes) or F (no) for all four walls, "
            f"as JSON:\n{self.example(scene)}"
        )

    def validate(self, value: Any, scene: Scene) -> dict[str, Any]:
        return validate_q2(value, scene)

    def expected(self, final: FinalState) -> dict[str, Any]:
        return {"answers": [label.model_dump() for label in final.q2]}
