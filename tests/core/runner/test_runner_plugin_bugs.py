"""A task whose messages() raises, or an adapter whose complete() returns something other than
a ModelResponse, stops the run with one PluginBug naming the plugin; before, the first was
recorded as an "api error" of the adapter (blamed on it, "re-run to resume") and the second
was an internal AttributeError."""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import pytest

from bpb_core import AdapterInfo, TaskInfo, hookimpl
from bpb_core.errors import PluginBug
from bpb_core.registry import PluginSource, make_registry
from bpb_core.runner import RunOptions, run_eval
from bpb_tasks.questions.question import BilliardsQuestion

ORIGIN = "plugin 'faulty' (faulty_hooks) from bpb-faulty 1.2"


class ExplodingTask(BilliardsQuestion):
    name: ClassVar[str] = "boom"
    default_cot: ClassVar[bool] = False
    title: ClassVar[str] = "Boom"

    def example(self, scene: Any) -> str:
        return '{"n": 0}'

    def question(self, scene: Any, options: Any) -> str:
        raise RuntimeError("question exploded")

    def validate(self, value: Any, scene: Any) -> dict[str, Any]:
        return {"n": value["n"]}

    def expected(self, truth: Any) -> dict[str, Any]:
        return {"n": 0}


class WordsAdapter:
    name = "words:x"

    async def complete(self, request: Any) -> Any:
        return '{"answers": []}'  # a bare string, not a ModelResponse


class Faulty:
    @hookimpl
    def bpb_eval_tasks(self) -> list[TaskInfo]:
        return [TaskInfo("boom", lambda: ExplodingTask, family="billiards")]

    @hookimpl
    def bpb_model_adapters(self) -> list[AdapterInfo]:
        return [AdapterInfo("words", lambda: lambda model, options: WordsAdapter())]


@pytest.fixture
def registry() -> Any:
    source = PluginSource("faulty", "bpb-faulty", "1.2", "faulty_hooks")
    return make_registry([(Faulty(), source)])


def test_a_task_whose_messages_raise_stops_the_run_naming_it(
    registry: Any, dataset: Path, tmp_path: Path
) -> None:
    options = RunOptions(tasks=("boom",), limit=1)
    with pytest.raises(PluginBug) as info:
        run_eval(dataset, "baseline:oracle", tmp_path / "run", options, registry=registry)
    assert str(info.value) == (
        f"{ORIGIN}: task 'boom': messages() raised RuntimeError: question exploded"
    )
    assert not list((tmp_path / "run").glob("h*/*/boom.json"))  # nothing recorded as answered


def test_an_adapter_returning_a_string_stops_the_run_naming_it(
    registry: Any, dataset: Path, tmp_path: Path
) -> None:
    options = RunOptions(tasks=("q2",), limit=1)
    with pytest.raises(PluginBug) as info:
        run_eval(dataset, "words:x", tmp_path / "run", options, registry=registry)
    assert str(info.value).startswith(
        f"{ORIGIN}: adapter 'words:x': complete() returned str; expected a bpb_core.ModelResponse"
    )
