"""Property tests: the vectorised scorers agree with the rules applied one row at a time, and
scoring does not depend on the order or padding of an answer."""

from __future__ import annotations

import random
from typing import Any

from hypothesis import given, settings, strategies as st

from bpb_tasks.q3.scorer import Q3Scorer
from bpb_tasks.questions.labels import Q1Scorer, Q2Scorer
from support.questions import questions
from support.reports_fixture import make_final, make_scene
from support.scoring import correct_by_unit, loop_correct, synthetic_units

SCORERS: dict[str, Any] = {"q1": Q1Scorer(), "q2": Q2Scorer(), "q3": Q3Scorer()}
SCENE = make_scene(2.0, 0)
FINAL = make_final(SCENE)
KEYS = {"q1": "answers", "q2": "answers", "q3": "predictions"}

TASKS = questions()


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(["q1", "q2", "q3"]), st.integers(1, 400), st.integers(0, 2**31))
def test_vectorised_score_equals_row_by_row_rules(task: str, rows: int, seed: int) -> None:
    frame = synthetic_units(task, rows, seed)
    vector = SCORERS[task].score(frame)["correct"].tolist()
    assert vector == loop_correct(frame, task)


def correct_of(task: str, answer: Any) -> list[bool]:
    return list(correct_by_unit(SCORERS[task], answer, FINAL, SCENE).values())


@settings(max_examples=60, deadline=None)
@given(st.sampled_from(["q1", "q2", "q3"]), st.randoms(use_true_random=False), st.data())
def test_order_and_unknown_entries_do_not_change_scores(
    task: str, rnd: random.Random, data: st.DataObject
) -> None:
    truth = TASKS[task].expected(FINAL)
    assert all(correct_of(task, truth))  # the truth itself is right everywhere
    entries = list(truth[KEYS[task]])
    rnd.shuffle(entries)
    junk = data.draw(
        st.lists(
            st.one_of(
                st.fixed_dictionaries({"id": st.integers(7, 99), "answer": st.just("T")}),
                st.fixed_dictionaries({"wall": st.sampled_from(["MIDDLE", "CEILING"])}),
                st.integers(),
                st.text(max_size=5),
            ),
            max_size=4,
        )
    )
    padded = {KEYS[task]: entries + junk, "extra": "ignored"}
    assert correct_of(task, padded) == correct_of(task, truth)
