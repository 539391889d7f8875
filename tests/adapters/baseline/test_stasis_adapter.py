"""``baseline:stasis`` end to end through the registry: nothing moves, nothing is hit."""

from __future__ import annotations

import asyncio
import json

from bpb_core import ModelRequest, make_registry
from bpb_tasks.billiards.scene import Ball, Scene


def _scene() -> Scene:
    balls = [Ball(id=0, pos=(0.5, 0.5), vel=(0.8, 0.1))]
    balls += [Ball(id=i, pos=(0.3 + 0.2 * i, 0.3)) for i in range(1, 7)]
    return Scene(scene_id="h2_0001", horizon=2.0, balls=balls)


def test_stasis_answers_no_contact_and_unmoved_for_every_task() -> None:
    adapter = make_registry().adapter("baseline:stasis")
    scene = _scene()

    def ask(task: str) -> dict[str, object]:
        reply = asyncio.run(adapter.complete(ModelRequest(messages=(), task=task, scene=scene)))
        data: dict[str, object] = json.loads(reply.text)
        return data

    assert ask("q1") == {"answers": [{"id": i, "answer": "F"} for i in range(1, 7)]}
    assert ask("q2") == {
        "answers": [{"wall": w, "answer": "F"} for w in ("TOP", "BOTTOM", "LEFT", "RIGHT")]
    }
    assert ask("q3") == {"predictions": [{"id": b.id, "pos": list(b.pos)} for b in scene.balls]}
