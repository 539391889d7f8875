"""The task: which object ball does the cue ball hit first in [0, t], or none?

The answer format is ``{"first": 3}`` or ``{"first": null}``. The prompt is the billiards
family's common text (table, balls, pockets, physics, horizon) plus this question; the expected
answer is cut from the ground truth's event log.
"""

from __future__ import annotations

import json
from typing import Any, ClassVar

from bpb_core import ParseFailure, PromptOptions
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.questions.answers import ball_id
from bpb_tasks.questions.question import BilliardsQuestion

CUE = 0


def first_hit(truth: FinalState) -> int | None:
    """The object ball in the first ball-ball event involving the cue ball, or ``None``."""
    for event in truth.events:
        if event.kind == "ball" and CUE in event.ids:
            return next(i for i in event.ids if i != CUE)
    return None


def validate(value: Any, scene: Scene) -> dict[str, Any]:
    """``{"first": <object ball id>}`` or ``{"first": null}``; anything else is a ParseFailure."""
    if not isinstance(value, dict) or "first" not in value:
        raise ParseFailure('firsthit: expected an object with the key "first"')
    raw = value["first"]
    if raw is None or (isinstance(raw, str) and raw.strip().lower() in ("none", "null")):
        return {"first": None}
    found = ball_id(raw)
    objects = sorted(b.id for b in scene.balls if b.id != CUE)
    if found not in objects:
        raise ParseFailure(f"firsthit: first: {raw!r} is not one of the object balls {objects}")
    return {"first": found}


class FirstHitTask(BilliardsQuestion):
    """Task plugin ``firsthit`` (chain of thought on by default, like Q1 and Q2)."""

    name: ClassVar[str] = "firsthit"
    default_cot: ClassVar[bool] = True
    title: ClassVar[str] = "First object ball hit"

    def example(self, scene: Scene) -> str:
        ids = sorted(b.id for b in scene.balls if b.id != CUE)
        return json.dumps({"first": ids[0] if ids else None})

    def question(self, scene: Scene, options: PromptOptions) -> str:
        ids = sorted(b.id for b in scene.balls if b.id != CUE)
        return (
            f"Which object ball {ids} does the cue ball (ball 0) touch first in "
            f"[0, {scene.horizon:g}] s? Give its id, or null if the cue ball touches no other "
            f"ball by then, as JSON:\n{self.example(scene)}"
        )

    def validate(self, value: Any, scene: Scene) -> dict[str, Any]:
        return validate(value, scene)

    def expected(self, truth: FinalState) -> dict[str, Any]:
        return {"first": first_hit(truth)}

    def answer_schema(self) -> dict[str, Any]:
        """The answer's JSON Schema: what ``--structured-output`` offers a provider."""
        return {
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "title": "firsthit answer",
            "type": "object",
            "properties": {
                "first": {
                    "anyOf": [{"type": "integer", "minimum": 1}, {"type": "null"}],
                    "description": "The first object ball the cue ball touches, or null",
                }
            },
            "required": ["first"],
            "additionalProperties": False,
        }
