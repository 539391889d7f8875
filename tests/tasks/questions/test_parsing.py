"""Answer extraction and validation: the paper's first-balanced-JSON rule, CoT, schemas."""

from __future__ import annotations

import contextlib
import json

import pytest
from hypothesis import given, settings, strategies as st

from bpb_core.errors import ParseFailure
from bpb_core.interfaces import PromptOptions
from bpb_core.reply_json import balanced_objects
from support.questions import questions
from support.runner_scenes import make_scene

SCENE = make_scene(3.0, 0)
TASKS = questions()
NO_COT, COT = PromptOptions(cot=False), PromptOptions(cot=True)
Q1 = {"answers": [{"id": i, "answer": "T" if i == 2 else "F"} for i in range(1, 7)]}
Q2 = {"answers": [{"wall": w, "answer": "F"} for w in ("TOP", "BOTTOM", "LEFT", "RIGHT")]}
Q3 = {"predictions": [{"id": i, "pos": [0.5 + 0.1 * i, 0.5]} for i in range(7)]}
VALID = {"q1": Q1, "q2": Q2, "q3": Q3}


def test_balanced_objects_ignore_braces_inside_strings() -> None:
    text = 'pre {"a": "x } y { z", "b": {"c": 1}} mid {oops post {"d": 2}'
    assert list(balanced_objects(text)) == ['{"a": "x } y { z", "b": {"c": 1}}', '{"d": 2}']


def test_first_rule_takes_the_first_object_as_the_paper_does() -> None:
    text = f"Sure! {json.dumps(Q1)} and later {json.dumps(Q1).replace('T', 'F')}"
    parsed = TASKS["q1"].parse(text, SCENE, NO_COT)
    assert parsed.rule == "first"
    assert parsed.value["answers"][1] == {"id": 2, "answer": "T"}


def test_first_rule_fails_when_the_first_object_is_not_the_answer() -> None:
    with pytest.raises(ParseFailure):
        TASKS["q1"].parse(f'{{"note": 1}} {json.dumps(Q1)}', SCENE, NO_COT)


def test_cot_reply_with_braces_in_reasoning_uses_last_valid_object() -> None:
    text = (
        'The format is {"answers": [...]} so I will reason. Velocity {vx, vy} = {0.3, -0.2}; '
        'a string "}" does not close. Draft: {"answers": [{"id": 1, "answer": "T"}]} is '
        f"incomplete.\nFinal answer:\n```json\n{json.dumps(Q1, indent=2)}\n```\nDone {{"
    )
    parsed = TASKS["q1"].parse(text, SCENE, COT)
    assert parsed.rule == "last-valid"
    assert parsed.value == Q1


def _latex_reasoning(groups: int) -> str:
    """Chain of thought as models write it: LaTeX (``\\frac{a}{b}`` is two groups), a
    piecewise ``\\left\\{`` that never closes, quoted labels, an odd inch mark and a sketch
    of the answer format, with ``groups`` ``{...}`` groups in all."""
    steps = [
        f"Step {k}: the cue ball travels $s_{{{k}}} = \\frac{{v_0^2 - v_{{{k}}}^2}}{{2 \\mu g}}$."
        for k in range(groups // 4)
    ]
    return (
        'The format is {"answers": [{"id": 1, "answer": "T or F"}, ...]}. '
        '$d = \\left\\{ 2R \\text{ if touching}$, so ball 3 is "T", 5" from the rail.\n'
        + "\n".join(steps)
        + "\nFinal answer:\n"
    )


def test_a_q1_reply_with_400_brace_groups_of_reasoning_parses() -> None:
    reasoning = _latex_reasoning(400)
    assert reasoning.count("}") >= 400
    text = f"{reasoning}```json\n{json.dumps(Q1, indent=2)}\n```\nThat is all."
    parsed = TASKS["q1"].parse(text, SCENE, COT)
    assert (parsed.value, parsed.rule) == (Q1, "last-valid")


def test_documented_tolerances_case_whitespace_and_string_ids() -> None:
    reply = {
        "answers": [{"id": str(i), "answer": " t " if i == 1 else "f"} for i in range(6, 0, -1)]
    }
    value = TASKS["q1"].parse(json.dumps(reply), SCENE, NO_COT).value
    assert value["answers"][0] == {"id": 1, "answer": "T"}
    assert [a["id"] for a in value["answers"]] == [1, 2, 3, 4, 5, 6]
    walls = {
        "answers": [{"wall": w.lower(), "answer": "F"} for w in ("RIGHT", "LEFT", "TOP", "BOTTOM")]
    }
    value = TASKS["q2"].parse(json.dumps(walls), SCENE, NO_COT).value
    assert [a["wall"] for a in value["answers"]] == ["TOP", "BOTTOM", "LEFT", "RIGHT"]


@pytest.mark.parametrize(
    ("task", "reply", "reason"),
    [
        ("q1", {"answers": Q1["answers"][:5]}, "missing [6]"),
        ("q1", {"answers": [*Q1["answers"], {"id": 1, "answer": "T"}]}, "more than once"),
        ("q1", {"answers": [{"id": 1, "answer": "yes"}, *Q1["answers"][1:]]}, "answers.0.answer"),
        ("q2", {"answers": Q2["answers"][:3]}, "walls must be"),
        ("q3", {"predictions": [{"id": i, "pos": None} for i in range(7)]}, "at least one"),
        (
            "q3",
            {"predictions": [{"id": 0, "pos": [2.5, 0.5]}, *Q3["predictions"][1:]]},
            "off the table",
        ),
        ("q3", {"predictions": Q3["predictions"][:6]}, "missing [6]"),
        (
            "q3",
            {"predictions": [{"id": 0, "pos": [1, "x"]}, *Q3["predictions"][1:]]},
            "two numbers",
        ),
    ],
)
def test_invalid_answers_fail_with_a_reason(task: str, reply: object, reason: str) -> None:
    with pytest.raises(ParseFailure, match=None) as failure:
        TASKS[task].parse(json.dumps(reply), SCENE, NO_COT)
    assert reason in str(failure.value)


def test_q3_accepts_null_for_pocketed_balls() -> None:
    reply = {"predictions": [{"id": i, "pos": None if i == 3 else [1.0, 0.5]} for i in range(7)]}
    value = TASKS["q3"].parse(json.dumps(reply), SCENE, NO_COT).value
    assert value["predictions"][3] == {"id": 3, "pos": None}


@settings(max_examples=300, deadline=None)
@given(text=st.text(alphabet=st.sampled_from('{}[]",:\\ natTF0123.-el' + "x\n"), max_size=300))
def test_parser_only_ever_raises_parse_failure(text: str) -> None:
    for task in TASKS.values():
        for options in (NO_COT, COT):
            with contextlib.suppress(ParseFailure):
                task.parse(text, SCENE, options)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=200))
def test_parser_on_arbitrary_unicode(text: str) -> None:
    for task in TASKS.values():
        with contextlib.suppress(ParseFailure):
            task.parse(text, SCENE, COT)


@settings(max_examples=150, deadline=None)
@given(
    task=st.sampled_from(["q1", "q2", "q3"]),
    before=st.text(max_size=80),
    noise=st.lists(
        st.sampled_from(["{", "}", '{"a": 1}', '"}"', "{x}", '"', "\\left\\{", "\\frac{a}{b}"]),
        max_size=12,
    ),
)
def test_cot_finds_the_answer_after_arbitrary_reasoning(
    task: str, before: str, noise: list[str]
) -> None:
    text = before + " ".join(noise) + "\nFinal: " + json.dumps(VALID[task])
    parsed = TASKS[task].parse(text, SCENE, COT)
    assert parsed.value == VALID[task]
