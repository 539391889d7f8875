"""Scoring rules against hand-worked examples: nulls, missing balls, extra keys, duplicate ids."""

from __future__ import annotations

from typing import Any

import pandas as pd
import pytest

from bpb_core.registry import Registry
from bpb_tasks.q3.scorer import Q3Scorer
from bpb_tasks.questions.labels import Q1Scorer, Q2Scorer
from support.reports_fixture import make_final, make_scene
from support.scoring import correct_by_unit, unit_frame

SCENE = make_scene(2.0, 0)  # truth: Q1 T for balls 1, 2; Q2 T for LEFT, TOP; ball 2 pocketed
FINAL = make_final(SCENE)
R = SCENE.physics.ball_radius


def scored(scorer: Any, answer: Any, status: str = "ok") -> dict[str, bool]:
    return correct_by_unit(scorer, answer, FINAL, SCENE, status)


def q1(**labels: Any) -> dict[str, Any]:
    return {"answers": [{"id": int(k[1:]), "answer": v} for k, v in labels.items()]}


PERFECT_Q1 = {"b1": "T", "b2": "T", "b3": "F", "b4": "F", "b5": "F", "b6": "F"}


def test_q1_perfect_answer_scores_every_ball() -> None:
    assert scored(Q1Scorer(), q1(**PERFECT_Q1)) == {str(k): True for k in range(1, 7)}


def test_q1_label_spelling_is_forgiven_but_garbage_is_wrong() -> None:
    answer = q1(**{**PERFECT_Q1, "b1": " t ", "b2": True, "b3": "false", "b4": "maybe"})
    result = scored(Q1Scorer(), answer)
    assert result == {"1": True, "2": True, "3": True, "4": False, "5": True, "6": True}


def test_q1_missing_ball_is_wrong_and_extra_ids_and_keys_are_ignored() -> None:
    labels = {k: v for k, v in PERFECT_Q1.items() if k != "b5"}
    answer = q1(**labels)
    answer["answers"] += [{"id": 0, "answer": "T"}, {"id": 7, "answer": "T"}, "junk"]
    answer["answers"][0]["confidence"] = 0.3
    answer["note"] = "extra top-level key"
    result = scored(Q1Scorer(), answer)
    assert result == {"1": True, "2": True, "3": True, "4": True, "5": False, "6": True}


def test_q1_duplicate_id_makes_that_ball_wrong_even_when_copies_agree() -> None:
    answer = q1(**PERFECT_Q1)
    answer["answers"].append({"id": "3", "answer": "F"})  # string id counts as ball 3
    assert scored(Q1Scorer(), answer)["3"] is False
    assert sum(scored(Q1Scorer(), answer).values()) == 5


@pytest.mark.parametrize("status", ["parse_error", "api_error", "missing"])
def test_non_ok_status_is_never_correct(status: str) -> None:
    assert not any(scored(Q1Scorer(), q1(**PERFECT_Q1), status).values())


@pytest.mark.parametrize("answer", [None, {}, {"answers": "T"}, {"answers": [1, 2]}])
def test_q1_null_or_malformed_answer_is_all_wrong(answer: Any) -> None:
    assert not any(scored(Q1Scorer(), answer).values())


def test_q2_walls_are_units_and_scene_needs_all_four() -> None:
    answer = {
        "answers": [
            {"wall": "top", "answer": "T"},
            {"wall": "LEFT", "answer": "T"},
            {"wall": "BOTTOM", "answer": "F"},
            {"wall": "MIDDLE", "answer": "T"},  # unknown wall: ignored
        ]
    }
    result = scored(Q2Scorer(), answer)
    assert result == {"TOP": True, "BOTTOM": True, "LEFT": True, "RIGHT": False}
    assert Q2Scorer.scene_rule == "all" and Q1Scorer.scene_rule == "mean"


def test_q2_duplicate_wall_is_wrong() -> None:
    answer = {"answers": [{"wall": w, "answer": "F"} for w in ("TOP", "TOP", "BOTTOM", "RIGHT")]}
    answer["answers"].append({"wall": "LEFT", "answer": "T"})
    assert scored(Q2Scorer(), answer) == {"TOP": False, "BOTTOM": True, "LEFT": True, "RIGHT": True}


def truth_positions() -> dict[int, Any]:
    return {p.id: p.pos for p in FINAL.predictions}


def test_q3_radius_rule_nulls_and_invalid_positions() -> None:
    truth = truth_positions()  # ball 2 is null (pocketed)
    preds: list[dict[str, Any]] = [
        {"id": 0, "pos": [truth[0][0] + R, truth[0][1]]},  # exactly R away: right
        {"id": 1, "pos": [truth[1][0] + 0.6 * R, truth[1][1] + 0.81 * R]},  # ~1.008 R: wrong
        {"id": 2, "pos": None},  # both null: right
        {"id": 3, "pos": None},  # null where the truth is a position: wrong
        {"id": 4, "pos": ["0.9", 0.5]},  # not numbers: wrong
        {"id": 5, "pos": [truth[5][0], truth[5][1]], "colour": "red"},  # extra key: fine
        # ball 6 missing: wrong
        {"id": 9, "pos": [1.0, 0.5]},  # unknown id: ignored
    ]
    result = scored(Q3Scorer(), {"predictions": preds})
    expected = {"0": True, "1": False, "2": True, "3": False, "4": False, "5": True, "6": False}
    assert result == expected


def test_q3_position_for_pocketed_ball_is_wrong_and_distance_reported() -> None:
    truth = truth_positions()
    preds = [{"id": k, "pos": list(v) if v else [1.1, 0.5]} for k, v in truth.items()]
    frame = unit_frame(Q3Scorer(), {"predictions": preds}, FINAL, SCENE)
    out = Q3Scorer().score(frame)
    assert out["correct"].tolist() == [True, True, False, True, True, True, True]
    assert out["distance"].iloc[0] == 0.0 and pd.isna(out["distance"].iloc[2])


def test_q3_duplicate_id_is_wrong() -> None:
    truth = truth_positions()
    preds = [{"id": k, "pos": list(v) if v else None} for k, v in truth.items()]
    preds.append({"id": 4, "pos": list(truth[4])})
    assert scored(Q3Scorer(), {"predictions": preds})["4"] is False


def test_scorers_are_registered_through_entry_points(registry: Registry) -> None:
    for task in ("q1", "q2", "q3"):
        scorer = registry.scorer_for(task)
        assert scorer.task == task
        assert registry.get("scorer", task).distribution == "bpb"
