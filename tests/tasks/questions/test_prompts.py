"""Prompts: built from the scene alone, stating the physics, in three input modes."""

from __future__ import annotations

import asyncio
import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from bpb_core.interfaces import PromptOptions
from bpb_core.model_calls import ImagePart, Message, ModelRequest, ModelResponse, TextPart
from bpb_core.registry import Registry
from bpb_core.runner import run_eval
from bpb_core.runner.options import RunOptions
from bpb_tasks.billiards.truth.final import FinalState
from support.questions import questions
from support.runner_scenes import make_scene, png_bytes

TASKS = questions()
SCENE = make_scene(3.0, 1)


def _text(messages: tuple[Message, ...]) -> str:
    return "\n".join(p.text for m in messages for p in m.parts if isinstance(p, TextPart))


@pytest.mark.parametrize("task", ["q1", "q2", "q3"])
def test_prompt_states_constants_laws_table_pockets_horizon_and_format(task: str) -> None:
    text = _text(TASKS[task].messages(SCENE, png_bytes(1), PromptOptions()))
    for needle in [
        "mu = 0.002",
        "g = 9.8",
        "v(s) = sqrt(v0^2 - 2*mu*g*s)",
        "v0^2 / (2*mu*g)",
        "R = 0.028575 m",
        "perfectly elastic",
        "(0, 0)",
        "(2, 1)",
        "radius 0.06 m",
        "t = 3 s",
        "x = 2",
        "y = 1",
        "scene h3_0001",
    ]:
        assert needle in text, needle
    example = {
        "q1": '{"answers": [{"id": 1, "answer": "T"}',
        "q2": '{"wall": "TOP"',
        "q3": '{"predictions": [{"id": 0, "pos": [',
    }[task]
    assert example in text


def test_input_modes_carry_image_and_or_state() -> None:
    task, image = TASKS["q1"], png_bytes(7)
    (img_only,) = task.messages(SCENE, image, PromptOptions(input_mode="image"))
    (both,) = task.messages(SCENE, image, PromptOptions(input_mode="image+state"))
    (state,) = task.messages(SCENE, None, PromptOptions(input_mode="state"))
    assert isinstance(img_only.parts[0], ImagePart) and img_only.parts[0].data == image
    state_json = json.dumps(list(SCENE.balls[0].vel))[1:-1]
    assert state_json not in _text((img_only,))
    assert isinstance(both.parts[0], ImagePart) and state_json in _text((both,))
    assert not any(isinstance(p, ImagePart) for p in state.parts) and state_json in _text((state,))


def test_cot_default_and_force_numeric_wording() -> None:
    q1, q3 = TASKS["q1"], TASKS["q3"]
    assert q1.default_cot and not q3.default_cot
    assert "Think step by step" in _text(q1.messages(SCENE, None, PromptOptions("state", True)))
    plain = _text(q3.messages(SCENE, None, PromptOptions("state")))
    forced = _text(q3.messages(SCENE, None, PromptOptions("state", force_numeric=True)))
    assert "null for a ball that was pocketed" in plain and "never null" in forced
    escalated = _text(q3.messages(SCENE, None, PromptOptions("state", escalation=2)))
    assert "could not be read" in escalated and "Reply with the JSON object only" in escalated


@pytest.mark.parametrize("escalation", [0, 2])
def test_force_numeric_examples_show_no_null(escalation: int) -> None:
    """--force-numeric asks for numbers for every ball: the JSON examples the model is told to
    copy (the question's and the exact shape of the last re-ask) must not show a null one."""
    q3 = TASKS["q3"]
    options = PromptOptions("state", force_numeric=True, escalation=escalation)
    forced = _text(q3.messages(SCENE, None, options))
    assert "never null" in forced and '"pos": null' not in forced
    plain = _text(q3.messages(SCENE, None, PromptOptions("state", escalation=escalation)))
    assert '"pos": null' in plain  # without the flag the example shows the pocketed form


@dataclass
class Recorder:
    """An adapter that records every prompt and answers nothing useful."""

    name: str = "recorder"
    seen: dict[tuple[str, str], tuple[Message, ...]] = field(default_factory=dict)

    async def complete(self, request: ModelRequest) -> ModelResponse:
        assert request.scene is not None
        self.seen[(request.scene.scene_id, request.task)] = request.messages
        await asyncio.sleep(0)
        return ModelResponse(text="{}", finish_reason="stop")


def _flip(final: FinalState) -> FinalState:
    q1 = [q.model_copy(update={"answer": "F" if q.answer == "T" else "T"}) for q in final.q1]
    preds = [p.model_copy(update={"pos": None}) for p in final.predictions]
    return final.model_copy(update={"q1": q1, "predictions": preds})


@pytest.mark.parametrize("mode", ["image", "state", "image+state"])
def test_prompt_never_depends_on_ground_truth(
    dataset: Path, tmp_path: Path, mode: str, registry: Registry
) -> None:
    other = tmp_path / "other"
    shutil.copytree(dataset, other)
    for final_path in other.glob("h*/scene_*/final.json"):
        flipped = _flip(FinalState.model_validate_json(final_path.read_text()))
        final_path.write_text(flipped.model_dump_json())
    options = RunOptions(input_mode=mode, retry=RunOptions().retry.__class__(max_reasks=0))
    first, second = Recorder(), Recorder()
    run_eval(dataset, first, tmp_path / "a", options, registry=registry)
    run_eval(other, second, tmp_path / "b", options, registry=registry)
    assert first.seen and first.seen == second.seen
    final = FinalState.model_validate_json((dataset / "h3/scene_0000/final.json").read_text())
    cue_final = next(p.pos for p in final.predictions if p.id == 0)
    assert cue_final is not None
    for messages in first.seen.values():
        assert f"{cue_final[0]}, {cue_final[1]}" not in _text(messages)
