"""``baseline:stasis`` end to end through the registry: nothing moves, nothing is hit."""

from __future__ import annotations

import asyncio
import json

from bpb_core import ModelRequest
from bpb_core.registry import Registry
from bpb_tasks.billiards.scene.model import Ball, Scene


def _scene() -> Scene:
    balls = [Ball(id=0, pos=(0.5, 0.5), vel=(0.8, 0.1))]
    balls += [Ball(id=i, pos=(0.3 + 0.2 * i, 0.3)) for i in range(1, 7)]
    return Scene(scene_id="h2_0001", horizon=2.0, balls=balls)


def test_stasis_answers_no_contact_and_unmoved_for_every_task(registry: Registry) -> None:
    adapter = registry.adapter("baseline:stasis")
    scene = _scene()

    def ask(task: str) -> dict[str, object]:
        reply = asyncio.run(
            adapter.complete(ModelRequest(messages=(), task=task, scene=scene, family="billiards"))
        )
        data: dict[str, object] = json.loads(reply.text)
        return data

    assert ask("q1") == {"answers": [{"id": i, "answer": "F"} for i in range(1, 7)]}
    assert ask("q2") == {
        "answers": [{"wall": w, "answer": "F"} for w in ("TOP", "BOTTOM", "LEFT", "RIGHT")]
    }
    assert ask("q3") == {"predictions": [{"id": b.id, "pos": list(b.pos)} for b in scene.balls]}


def test_a_prediction_the_family_does_not_offer_is_a_rejected_request(registry: Registry) -> None:
    import pytest

    from bpb_core.errors import RequestRejected

    adapter = registry.adapter("baseline:stasis")
    request = ModelRequest(messages=(), task="q1", scene=_scene())  # no family named
    with pytest.raises(RequestRejected, match="needs the scene and its family"):
        asyncio.run(adapter.complete(request))
