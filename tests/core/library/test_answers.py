"""score_answer and build_messages agree with what bpb run sends and bpb report scores."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from bpb_core import RunOptions, build_messages, load_dataset, run_eval, score_answer
from bpb_core.errors import BadInput
from bpb_core.model_calls import ModelRequest, ModelResponse, Usage
from bpb_core.registry import Registry
from bpb_core.results.tables import scene_scores


class Recorder:
    """Answers every request with one reply; keeps the first request of each (scene, task)."""

    name = "recorder"

    def __init__(self, reply: str) -> None:
        self.reply = reply
        self.sent: dict[tuple[str, str], ModelRequest] = {}

    async def complete(self, request: ModelRequest) -> ModelResponse:
        self.sent.setdefault((request.scene.scene_id, request.task), request)
        return ModelResponse(self.reply, Usage(), None, 0.0, "recorder")


REPLY = '{"answers": [{"id": 1, "answer": "T"}, {"wall": "TOP", "answer": "T"}]}'


def test_messages_are_what_a_run_sends_and_scores_what_a_report_scores(
    small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    partial = (
        '{"answers": ['
        + ", ".join(f'{{"id": {i}, "answer": "{"T" if i % 2 else "F"}"}}' for i in range(1, 7))
        + "]}"
    )
    adapter = Recorder(partial)
    options = RunOptions(tasks=("q1", "q3"), cot={"q1": False})
    result = run_eval(str(small_dataset), adapter, tmp_path / "run", options, registry=registry)
    per_scene = scene_scores(result.scores).set_index(["scene_id", "task"])["score"]
    data = load_dataset(small_dataset, registry=registry)
    for scene in data:
        for task in ("q1", "q3"):
            sent = adapter.sent[(scene.scene_id, task)].messages
            cot = False if task == "q1" else None
            assert sent == build_messages(task, scene, "image", cot=cot, registry=registry)
            mine = score_answer(task, scene, partial, cot=cot, registry=registry)
            assert mine.score == pytest.approx(per_scene[(scene.scene_id, task)])
    assert score_answer("q1", data["h1_0000"], partial).status == "ok"
    assert score_answer("q3", data["h1_0000"], partial).status == "parse_error"


def test_unknown_image_kind_names_the_kinds(small_dataset: Path) -> None:
    scene = load_dataset(small_dataset)["h1_0001"]
    with pytest.raises(BadInput, match=r"h1_0001: image kind 'depth'.*input, init, final"):
        scene.image_path("depth")
    assert scene.image_path("final.png").name == "final.png"


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(text=st.one_of(st.text(max_size=200), st.just(REPLY)))
def test_any_reply_text_gets_a_score_in_range(small_dataset: Path, text: str) -> None:
    scene = load_dataset(small_dataset)["h3_0002"]
    for task in ("q1", "q2", "q3"):
        scored = score_answer(task, scene, text)
        assert scored.status in ("ok", "parse_error")
        assert 0.0 <= scored.score <= 1.0
        assert (scored.status == "ok") == (scored.answer is not None)
        if scored.status == "parse_error":
            assert scored.score == 0.0 and not any(u.correct for u in scored.units)


def test_expected_answer_scores_full_marks(small_dataset: Path, registry: Registry) -> None:
    for scene in load_dataset(small_dataset, registry=registry):
        for task in ("q1", "q2", "q3"):
            right = json.dumps(registry.task(task).expected(scene.truth))
            assert score_answer(task, scene, right, registry=registry).score == 1.0


def test_an_unknown_input_mode_is_refused(
    small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    """build_messages and run_eval took input_mode='video': the messages carried the image and
    the run went through, recording 'video' in run.json (the command line offers only three)."""
    scene = load_dataset(small_dataset)["h1_0000"]
    with pytest.raises(BadInput, match=r"--input-mode: must be one of image, image\+state, state"):
        build_messages("q1", scene, "video", registry=registry)  # type: ignore[arg-type]
    with pytest.raises(BadInput, match="got 'video'"):
        options = RunOptions(limit=1, input_mode="video")  # type: ignore[arg-type]
        run_eval(small_dataset, "baseline:oracle", tmp_path / "run", options, registry=registry)
    assert not (tmp_path / "run" / "run.json").exists()
