"""A task's expected() that raises inside a baseline is blamed on the task's plugin, not on the
adapter; one returning what the task's own parser refuses stops the oracle naming the task.

Before, the first was recorded per pair as "adapter baseline:oracle raised ..." (an api error)
and the second gave the oracle parse errors with no warning: a 0% oracle."""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import pytest

from bpb_adapters.baseline.adapter import BaselineAdapter
from bpb_core import TaskInfo, hookimpl
from bpb_core.errors import PluginBug
from bpb_core.registry import PluginSource, Registry, make_registry
from bpb_core.runner import RunOptions, run_eval
from bpb_tasks.questions.question import BilliardsQuestion

ORIGIN = "plugin 'faulty' (faulty_hooks) from bpb-faulty 1.2"


class CountTask(BilliardsQuestion):
    name: ClassVar[str] = "count"
    default_cot: ClassVar[bool] = False
    title: ClassVar[str] = "Count"
    answer: ClassVar[Any] = {"n": 0}

    def example(self, scene: Any) -> str:
        return '{"n": 0}'

    def question(self, scene: Any, options: Any) -> str:
        return f"Say n.\n{self.example(scene)}"

    def validate(self, value: Any, scene: Any) -> dict[str, Any]:
        if not isinstance(value, dict) or not isinstance(value.get("n"), int):
            from bpb_core.errors import ParseFailure

            raise ParseFailure("need an integer n")
        return {"n": value["n"]}

    def expected(self, truth: Any) -> Any:
        return self.answer


class RaisingTask(CountTask):
    name: ClassVar[str] = "raising"

    def expected(self, truth: Any) -> Any:
        raise ZeroDivisionError("expected exploded")


class WrongTypeTask(CountTask):
    name: ClassVar[str] = "wrongtype"
    answer: ClassVar[Any] = 42


class NotJsonTask(CountTask):
    name: ClassVar[str] = "notjson"
    answer: ClassVar[Any] = {"n": {1, 2}}


class Faulty:
    @hookimpl
    def bpb_eval_tasks(self) -> list[TaskInfo]:
        made = (CountTask, RaisingTask, WrongTypeTask, NotJsonTask)
        return [TaskInfo(cls.name, lambda cls=cls: cls, family="billiards") for cls in made]


@pytest.fixture
def registry() -> Registry:
    return make_registry([(Faulty(), PluginSource("faulty", "bpb-faulty", "1.2", "faulty_hooks"))])


def _run(registry: Registry, dataset: Path, out: Path, task: str, model: str = "oracle") -> Any:
    adapter = BaselineAdapter(f"baseline:{model}", model, _registry=registry)
    options = RunOptions(tasks=(task,), limit=1, concurrency=1)
    return run_eval(dataset, adapter, out, options, registry=registry)


def test_a_good_task_is_answered_by_the_oracle(
    registry: Registry, dataset: Path, tmp_path: Path
) -> None:
    result = _run(registry, dataset, tmp_path / "run", "count")
    assert result.statuses["count"]["ok"] == 2


@pytest.mark.parametrize("model", ["oracle", "stasis"])
def test_expected_raising_names_the_task_plugin(
    registry: Registry, dataset: Path, tmp_path: Path, model: str
) -> None:
    with pytest.raises(PluginBug) as info:
        _run(registry, dataset, tmp_path / "run", "raising", model)
    assert str(info.value) == (
        f"{ORIGIN}: task 'raising': expected() raised ZeroDivisionError: expected exploded"
    )


def test_the_oracle_refuses_an_expected_answer_its_task_cannot_parse(
    registry: Registry, dataset: Path, tmp_path: Path
) -> None:
    with pytest.raises(PluginBug) as info:
        _run(registry, dataset, tmp_path / "run", "wrongtype")
    assert str(info.value).startswith(
        f"{ORIGIN}: task 'wrongtype': expected() returned 42, which the task's own parser refuses: "
    )
    assert not list((tmp_path / "run").glob("h*/*/wrongtype.json"))  # no parse errors recorded


def test_expected_returning_what_json_cannot_hold_names_the_task_plugin(
    registry: Registry, dataset: Path, tmp_path: Path
) -> None:
    with pytest.raises(PluginBug) as info:
        _run(registry, dataset, tmp_path / "run", "notjson")
    assert str(info.value) == (
        f"{ORIGIN}: task 'notjson': expected() returned what JSON cannot hold: "
        "Object of type set is not JSON serializable"
    )
