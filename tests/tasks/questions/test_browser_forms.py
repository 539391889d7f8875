"""The billiards questions' browser forms: what the widgets need, and posted fields to answers."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings, strategies as st

from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.q3.task import Q3Task
from support.questions import questions
from support.runner_scenes import make_scene

SCENE = make_scene(1.0, 0)
NAMES = ["ball1", "ball2", "ball6", "TOP", "LEFT", "none", "pos0", "pos3", "pos6", "x", ""]
VALUES = ["T", "F", "pocket", "0.5,0.5", "1e9,0", "nan,1", "0.1,0.2,0.3", "", "<b>"]


@settings(max_examples=300, deadline=None)
@given(
    task=st.sampled_from(["q1", "q2", "q3"]),
    fields=st.dictionaries(
        st.sampled_from(NAMES) | st.text(max_size=8),
        st.sampled_from(VALUES) | st.text(max_size=12),
        max_size=9,
    ),
)
def test_any_posted_fields_give_a_valid_answer_or_a_named_error(
    task: str, fields: dict[str, str]
) -> None:
    question = questions()[task]
    try:
        answer = question.read_form(fields, SCENE)
    except ValueError as exc:
        named = any(str(exc).startswith(f"{key}: ") for key in fields)
        assert named or "missing" in str(exc)  # names the posted field, or the missing one
        return
    assert question.validate(answer, SCENE) == answer  # the task's own validator agrees


def test_ticks_and_places_become_the_answer_format() -> None:
    q1, q2, q3 = (questions()[t] for t in ("q1", "q2", "q3"))
    q1_answer = q1.read_form({"ball2": "T", "ball5": "T"}, SCENE)["answers"]
    assert [a["answer"] for a in q1_answer] == ["F", "T", "F", "F", "T", "F"]
    q2_answer = q2.read_form({"LEFT": "T"}, SCENE)["answers"]
    assert {a["wall"]: a["answer"] for a in q2_answer} == {
        "TOP": "F",
        "BOTTOM": "F",
        "LEFT": "T",
        "RIGHT": "F",
    }
    places = {f"pos{b.id}": "0.25,0.75" for b in SCENE.balls} | {"pos4": "pocket"}
    predictions = q3.read_form(places, SCENE)["predictions"]
    assert predictions[4] == {"id": 4, "pos": None} and predictions[0]["pos"] == [0.25, 0.75]
    with pytest.raises(ValueError, match="pos6: missing"):
        q3.read_form({k: v for k, v in places.items() if k != "pos6"}, SCENE)
    with pytest.raises(ValueError, match="off the table"):
        q3.read_form(places | {"pos1": "2.5,0.5"}, SCENE)


def test_an_untouched_form_is_no_answer_and_none_must_be_said() -> None:
    q1, q2, q3 = (questions()[t] for t in ("q1", "q2", "q3"))
    for question in (q1, q2):
        with pytest.raises(ValueError, match="none: missing"):
            question.read_form({}, SCENE)  # nothing ticked is not "no contact"
        answers = question.read_form({"none": "T"}, SCENE)["answers"]
        assert {a["answer"] for a in answers} == {"F"}
    with pytest.raises(ValueError, match="none: ticked together with ball2"):
        q1.read_form({"none": "T", "ball2": "T"}, SCENE)
    untouched = {f"pos{b.id}": "" for b in SCENE.balls}  # what an untouched page posts
    with pytest.raises(ValueError, match=r"pos0: missing \(place ball 0 or confirm it rests"):
        q3.read_form(untouched, SCENE)


def test_drag_markers_sit_on_the_image_frame(small_dataset: Path) -> None:
    folder = sorted(small_dataset.glob("h1/scene_*"))[0]
    scene = Scene.model_validate_json((folder / "init.json").read_bytes())
    context = Q3Task().form_context(scene, (folder / "init.png").read_bytes())
    assert context["frame"] == {"x0": 116.0, "y0": 684.0, "ppm": 600.0}  # default image config
    assert [b["id"] for b in context["balls"]] == list(range(7))
    assert Q3Task().form_context(scene, b"not a png")["frame"] is None  # numbers instead
