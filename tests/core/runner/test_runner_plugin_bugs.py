"""A task whose messages() raises, or an adapter whose complete() returns something other than
a ModelResponse, stops the run with one PluginBug naming the plugin; before, the first was
recorded as an "api error" of the adapter (blamed on it, "re-run to resume") and the second
was an internal AttributeError.

An adapter that cannot make a call at all (its factory returns None, it has no complete(), its
complete() is not async) is refused before the first call; before, every call was recorded as
an API error and the summary said "failed on infrastructure, re-run to resume". An adapter
whose complete() raises something other than a bpb model error stops the run the same way, and
so does a task whose messages() return no messages (not blamed on the adapter), or whose
parse() raises anything but a ParseFailure or returns no ParsedAnswer (in score_answer too), or
whose answer_schema() raises or returns no dict with --structured-output (in answer_schema too).
An adapter whose settings() JSON cannot hold is named before the run folder is made."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, ClassVar

import pytest

from bpb_core import (
    AdapterInfo,
    ModelResponse,
    TaskInfo,
    Usage,
    answer_schema,
    build_messages,
    hookimpl,
    load_dataset,
    run_eval as library_run_eval,
    score_answer,
)
from bpb_core.errors import BadInput, PluginBug
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


class BadParseTask(ExplodingTask):
    """Its parse() raises or returns a bare dict, its messages() a str, its answer_schema()
    raises or returns the schema's JSON text, as ``flaw`` says."""

    name: ClassVar[str] = "badparse"
    flaw: ClassVar[str] = ""

    def question(self, scene: Any, options: Any) -> str:
        return f"Say n.\n{self.example(scene)}"

    def messages(self, scene: Any, image: bytes | None, options: Any) -> Any:
        if self.flaw == "messages_type":
            return "Say n."
        return super().messages(scene, image, options)

    def parse(self, text: str, scene: Any, options: Any) -> Any:
        if self.flaw == "raise":
            raise RuntimeError("parse exploded")
        if self.flaw == "type":
            return {"n": 0}
        return super().parse(text, scene, options)

    def answer_schema(self) -> Any:
        if self.flaw == "schema_raise":
            raise RuntimeError("schema exploded")
        schema = {"type": "object", "properties": {"n": {"type": "integer"}}}
        return json.dumps(schema) if self.flaw == "schema_type" else schema


class ReplyAdapter:
    name = "reply:x"

    async def complete(self, request: Any) -> Any:
        return ModelResponse('{"n": 0}', Usage(), None, 0.0, "reply")


class SchemaAdapter:
    """Sends the task's schema on, as a provider's adapter does with --structured-output."""

    name = "schema:x"

    async def complete(self, request: Any) -> Any:
        assert request.response_schema.get("type") == "object"
        return ModelResponse('{"n": 0}', Usage(), None, 0.0, "schema")


class SetSettings(ReplyAdapter):
    """Its settings hold a set, which JSON (and so run.json) cannot."""

    name = "settings:x"

    def settings(self) -> Any:
        return {"stop": {"END"}}


class WordsAdapter:
    name = "words:x"

    async def complete(self, request: Any) -> Any:
        return '{"answers": []}'  # a bare string, not a ModelResponse


class NoComplete:
    name = "nocall:x"


class SyncComplete:
    name = "sync:x"

    def complete(self, request: Any) -> Any:
        raise AssertionError("never called")


class RaisingAdapter:
    name = "raising:x"

    async def complete(self, request: Any) -> Any:
        raise KeyError("oops")


def _factory(made: Any) -> Any:
    return lambda: lambda model, options: made


class Faulty:
    @hookimpl
    def bpb_eval_tasks(self) -> list[TaskInfo]:
        return [
            TaskInfo("boom", lambda: ExplodingTask, family="billiards"),
            TaskInfo("badparse", lambda: BadParseTask, family="billiards"),
        ]

    @hookimpl
    def bpb_model_adapters(self) -> list[AdapterInfo]:
        return [
            AdapterInfo("words", _factory(WordsAdapter())),
            AdapterInfo("none", _factory(None)),
            AdapterInfo("nocall", _factory(NoComplete())),
            AdapterInfo("sync", _factory(SyncComplete())),
            AdapterInfo("raising", _factory(RaisingAdapter())),
            AdapterInfo("reply", _factory(ReplyAdapter())),
            AdapterInfo("schema", _factory(SchemaAdapter())),
            AdapterInfo("settings", _factory(SetSettings())),
        ]


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


@pytest.mark.parametrize(
    ("flaw", "said"),
    [
        ("raise", "parse() raised RuntimeError: parse exploded"),
        ("type", "parse() returned dict; expected a bpb_core.ParsedAnswer with a dict value"),
    ],
)
def test_a_task_whose_parse_raises_or_returns_no_parsed_answer_stops_the_run_naming_it(
    monkeypatch: pytest.MonkeyPatch, registry: Any, dataset: Path, small_dataset: Path,
    tmp_path: Path, flaw: str, said: str,
) -> None:  # fmt: skip
    """Before, the exception (or "'dict' object has no attribute 'rule'") left the run as an
    internal error with a traceback, naming no plugin."""
    monkeypatch.setattr(BadParseTask, "flaw", flaw)
    options = RunOptions(tasks=("badparse",), limit=1)
    with pytest.raises(PluginBug) as info:
        run_eval(dataset, "reply:x", tmp_path / "run", options, registry=registry)
    assert str(info.value) == f"{ORIGIN}: task 'badparse': {said}"
    assert not list((tmp_path / "run").glob("h*/*/badparse.json"))
    scene = load_dataset(small_dataset, registry=registry)["h1_0000"]
    with pytest.raises(PluginBug) as info:
        score_answer("badparse", scene, '{"n": 0}', registry=registry)
    assert str(info.value) == f"{ORIGIN}: task 'badparse': {said}"


def test_a_task_whose_messages_are_no_messages_is_named_not_the_adapter(
    monkeypatch: pytest.MonkeyPatch, registry: Any, dataset: Path, small_dataset: Path,
    tmp_path: Path,
) -> None:  # fmt: skip
    """Before, the run blamed the adapter that choked on them ("adapter 'baseline:vision':
    complete() raised AttributeError: 'str' object has no attribute 'parts'") and
    build_messages handed the string back."""
    monkeypatch.setattr(BadParseTask, "flaw", "messages_type")
    said = (
        f"{ORIGIN}: task 'badparse': messages() returned str; expected a tuple of bpb_core.Message"
    )
    options = RunOptions(tasks=("badparse",), limit=1)
    with pytest.raises(PluginBug) as info:
        run_eval(dataset, "baseline:vision", tmp_path / "run", options, registry=registry)
    assert str(info.value) == said
    scene = load_dataset(small_dataset, registry=registry)["h1_0000"]
    with pytest.raises(PluginBug) as info:
        build_messages("badparse", scene, registry=registry)
    assert str(info.value) == said


@pytest.mark.parametrize(
    ("flaw", "said"),
    [
        ("schema_raise", "answer_schema() raised RuntimeError: schema exploded"),
        ("schema_type", "answer_schema() returned str; expected a dict (a JSON Schema)"),
    ],
)
def test_a_task_whose_answer_schema_is_no_dict_is_named_not_the_adapter(
    monkeypatch: pytest.MonkeyPatch, registry: Any, dataset: Path, tmp_path: Path, flaw: str,
    said: str,
) -> None:  # fmt: skip
    """Before, with --structured-output the adapter that choked on the schema was blamed
    ("adapter 'schema:x': complete() raised AttributeError"), and a raise left the run as an
    internal error naming no plugin."""
    options = RunOptions(tasks=("badparse",), limit=1, structured_output=True)
    good = run_eval(dataset, "schema:x", tmp_path / "good", options, registry=registry)
    assert {status for status, n in good.statuses["badparse"].items() if n} == {"ok"}
    monkeypatch.setattr(BadParseTask, "flaw", flaw)
    with pytest.raises(PluginBug) as info:
        run_eval(dataset, "schema:x", tmp_path / "run", options, registry=registry)
    assert str(info.value) == f"{ORIGIN}: task 'badparse': {said}"
    assert not list((tmp_path / "run").glob("h*/*/badparse.json"))
    with pytest.raises(PluginBug) as info:
        answer_schema("badparse", registry=registry)
    assert str(info.value) == f"{ORIGIN}: task 'badparse': {said}"


def test_adapter_settings_json_cannot_hold_are_named_before_the_run_folder_is_made(
    registry: Any, dataset: Path, tmp_path: Path
) -> None:
    """Before, writing run.json raised "TypeError: Object of type set is not JSON serializable"
    (naming no plugin) and left a run folder without a run.json."""
    options = RunOptions(tasks=("q2",), limit=1)
    with pytest.raises(PluginBug) as info:
        run_eval(dataset, "settings:x", tmp_path / "run", options, registry=registry)
    assert str(info.value) == (
        f"{ORIGIN}: adapter 'settings:x': settings() returned settings run.json cannot hold "
        "(Object of type set is not JSON serializable); expected a dict of JSON values"
    )
    assert not (tmp_path / "run").exists()


def test_an_adapter_returning_a_string_stops_the_run_naming_it(
    registry: Any, dataset: Path, tmp_path: Path
) -> None:
    options = RunOptions(tasks=("q2",), limit=1)
    with pytest.raises(PluginBug) as info:
        run_eval(dataset, "words:x", tmp_path / "run", options, registry=registry)
    assert str(info.value).startswith(
        f"{ORIGIN}: adapter 'words:x': complete() returned str; expected a bpb_core.ModelResponse"
    )


@pytest.mark.parametrize(
    ("spec", "returned"),
    [
        ("none:x", "None"),
        ("nocall:x", "a NoComplete without a complete() method"),
        ("sync:x", "a SyncComplete whose complete() is not async"),
    ],
)
def test_an_adapter_that_cannot_call_is_refused_before_the_first_call(
    registry: Any, dataset: Path, tmp_path: Path, spec: str, returned: str
) -> None:
    options = RunOptions(tasks=("q2",), limit=1)
    with pytest.raises(PluginBug) as info:
        run_eval(dataset, spec, tmp_path / "run", options, registry=registry)
    assert str(info.value) == (
        f"{ORIGIN}: the adapter factory for {spec!r} returned {returned}; "
        "expected an object with an async complete(request)"
    )
    assert not (tmp_path / "run").exists()  # refused before the run folder was made


@pytest.mark.parametrize("made", [None, NoComplete(), SyncComplete()])
def test_an_adapter_object_that_cannot_call_is_bad_input(
    registry: Any, dataset: Path, tmp_path: Path, made: Any
) -> None:
    options = RunOptions(tasks=("q2",), limit=1)
    with pytest.raises(BadInput, match=r"expected an object with an async complete\(request\)$"):
        run_eval(dataset, made, tmp_path / "run", options, registry=registry)
    assert not (tmp_path / "run").exists()


def test_an_adapter_whose_complete_raises_stops_the_run_naming_it(
    registry: Any, dataset: Path, tmp_path: Path
) -> None:
    options = RunOptions(tasks=("q2",), limit=2, concurrency=1)
    with pytest.raises(PluginBug) as info:
        run_eval(dataset, "raising:x", tmp_path / "run", options, registry=registry)
    assert str(info.value) == (f"{ORIGIN}: adapter 'raising:x': complete() raised KeyError: 'oops'")
    assert not list((tmp_path / "run").glob("h*/*/q2.json"))  # no "api error" recorded


def test_an_adapter_object_whose_complete_raises_stops_the_run(
    registry: Any, dataset: Path, tmp_path: Path
) -> None:
    options = RunOptions(tasks=("q2",), limit=1)
    with pytest.raises(PluginBug, match=r"adapter 'raising:x': complete\(\) raised KeyError"):
        run_eval(dataset, RaisingAdapter(), tmp_path / "run", options, registry=registry)


class MyWords(WordsAdapter):
    name = "mine:x"  # no plugin registers "mine"


@pytest.mark.parametrize(("made", "said"), [
    (MyWords(), "adapter 'mine:x': complete() returned str; expected a bpb_core.ModelResponse "
     "(text a str, usage a bpb_core.Usage)"),
    (RaisingAdapter(), "adapter 'raising:x': complete() raised KeyError: 'oops'"),
])  # fmt: skip
def test_the_library_names_an_unregistered_adapter_object_once_by_its_module(
    dataset: Path, tmp_path: Path, made: Any, said: str
) -> None:
    # before: "'mine:x': adapter 'mine:x': ..." (the name twice, and no hint where it lives)
    options = RunOptions(tasks=("q2",), limit=1)
    with pytest.raises(PluginBug) as info:
        library_run_eval(dataset, made, tmp_path / "run", options, registry=make_registry())
    assert str(info.value) == f"module {__name__!r}: {said}"
