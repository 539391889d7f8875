"""The answer JSON Schemas in docs/schemas are the code's, and every answer bpb accepts fits."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from bpb_core import PromptOptions, answer_schema, load_dataset, make_registry
from bpb_core.errors import BadInput, ParseFailure
from bpb_core.registry import Registry
from support.paths import DOCS

TASKS = ("q1", "q2", "q3")


@pytest.mark.parametrize("task", TASKS)
def test_published_schema_is_the_code(task: str) -> None:
    # Regenerate: json.dumps(bpb_core.answer_schema(task), indent=2, sort_keys=True) + "\n"
    path = DOCS / "schemas" / f"{task}.answer.schema.json"
    assert json.loads(path.read_text()) == answer_schema(task)
    jsonschema.Draft202012Validator.check_schema(answer_schema(task))


def test_expected_answers_fit_and_wrong_shapes_do_not(
    small_dataset: Path, registry: Registry
) -> None:
    validators = {t: jsonschema.Draft202012Validator(answer_schema(t)) for t in TASKS}
    for scene in load_dataset(small_dataset, registry=registry):
        for task in TASKS:
            validators[task].validate(registry.task(task).expected(scene.truth))
    assert not validators["q1"].is_valid({"answers": [{"id": 1, "answer": "yes"}]})
    assert not validators["q2"].is_valid({"answers": [{"wall": "NORTH", "answer": "T"}]})
    assert not validators["q3"].is_valid({"predictions": [{"id": 0, "pos": [1.0]}]})
    assert not validators["q3"].is_valid({"predictions": [], "extra": 1})


def test_a_task_without_a_schema_is_named(registry: Registry) -> None:
    class Plain:
        name = "plain"
        default_cot = False

    with pytest.raises(BadInput, match="task 'plain': publishes no answer schema"):
        answer_schema(Plain(), registry=registry)  # type: ignore[arg-type]


LABEL = st.sampled_from(["T", "F", "t", " f ", "yes", 1, None])


@settings(
    max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    ids=st.lists(st.one_of(st.integers(0, 7), st.sampled_from(["3", "ball 4"])), max_size=8),
    labels=st.lists(LABEL, min_size=8, max_size=8),
)
def test_every_answer_the_parser_accepts_fits_the_schema(
    small_dataset: Path, ids: list[object], labels: list[object]
) -> None:
    scene = load_dataset(small_dataset)["h1_0000"]
    value = {"answers": [{"id": i, "answer": a} for i, a in zip(ids, labels, strict=False)]}
    task = make_registry().task("q1")
    try:
        parsed = task.parse(json.dumps(value), scene.state, PromptOptions())
    except ParseFailure:
        return
    jsonschema.validate(parsed.value, answer_schema(task))
