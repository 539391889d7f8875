"""Q3: every ball's centre at the horizon, ``null`` for a pocketed ball."""

from __future__ import annotations

import json
from typing import Any, ClassVar

from bpb_core.interfaces import PromptOptions
from bpb_core.scene import FinalState, Scene
from bpb_tasks.answers import validate_q3
from bpb_tasks.prompting_task import BuiltinTask


class Q3Task(BuiltinTask):
    """Final positions of all balls (chain of thought off by default, as in the paper)."""

    name: ClassVar[str] = "q3"
    default_cot: ClassVar[bool] = False
    title: ClassVar[str] = "Final positions"

    def example(self, scene: Scene) -> str:
        ids = sorted(b.id for b in scene.balls)
        items: list[dict[str, Any]] = [{"id": i, "pos": [1.2345, 0.5]} for i in ids]
        if len(items) > 1:
            items[-1]["pos"] = None
        return json.dumps({"predictions": items})

    def question(self, scene: Scene, options: PromptOptions) -> str:
        ids = sorted(b.id for b in scene.balls)
        w, h = scene.table.width, scene.table.height
        text = (
            f"Where is the centre of every ball {ids} at t = {scene.horizon:g} s? Give [x, y] in "
            f"metres (x in [0, {w:g}], y in [0, {h:g}], up to 4 decimals)"
        )
        if options.force_numeric:
            text += (
                ". Give numeric coordinates for every ball, never null: if you think a ball was "
                "pocketed, give your best estimate of where it is"
            )
        else:
            text += ", or null for a ball that was pocketed"
        return f"{text}. Answer as JSON:\n{self.example(scene)}"

    def validate(self, value: Any, scene: Scene) -> dict[str, Any]:
        return validate_q3(value, scene)

    def expected(self, final: FinalState) -> dict[str, Any]:
        return {
            "predictions": [
                {"id": p.id, "pos": None if p.pos is None else list(p.pos)}
                for p in final.predictions
            ]
        }
