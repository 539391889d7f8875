"""A task whose browser form hooks (form_context(), its form_template, read_form()) raise or
give the wrong type makes ``bpb human`` show one line naming the task's plugin and the hook
(status 500), and store nothing.

Before, each was a bare "Internal Server Error" with a traceback in the terminal (a
form_context() of a list or holding ``prefix``, a template naming an undefined value, a
read_form() raising KeyError); a read_form() returning a str was refused as the person's bad
answer (400, "badform: ...": the text did not parse), blaming them for the task's bug.
"""

from __future__ import annotations

import html
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import pytest
from starlette.testclient import TestClient

from bpb_core import TaskInfo, hookimpl
from bpb_core.registry import PluginSource, make_registry
from bpb_core.run_folder import iter_answers
from bpb_core.runner.options import RunOptions
from bpb_core.web.human import HumanSession, human_app
from bpb_tasks.questions.question import Q2Task

ORIGIN = "plugin 'formless' (formless_hooks) from bpb-formless 0.2"
TASK = "task 'badform'"


class BadFormTask(Q2Task):
    """Q2 under another name, whose form hooks break as ``flaw`` says."""

    name: ClassVar[str] = "badform"
    flaw: ClassVar[str] = ""

    @property
    def form_template(self) -> str:  # type: ignore[override]
        return (
            "{{ no_such_value }}" if self.flaw == "template_undefined" else Q2Task().form_template
        )

    def form_context(self, scene: Any, image: bytes | None) -> Any:
        if self.flaw == "context_raise":
            raise RuntimeError("context exploded")
        context = super().form_context(scene, image)
        if self.flaw == "context_reserved":
            return {**context, "prefix": "mine."}
        return list(context) if self.flaw == "context_type" else context

    def read_form(self, fields: Mapping[str, str], scene: Any) -> Any:
        if self.flaw == "read_raise":
            raise KeyError("TOP")
        answer = super().read_form(fields, scene)
        return str(answer) if self.flaw == "read_type" else answer


class Formless:
    @hookimpl
    def bpb_eval_tasks(self) -> list[TaskInfo]:
        return [TaskInfo("badform", lambda: BadFormTask, family="billiards")]


def _client(data: Path, run: Path) -> TestClient:
    source = PluginSource("formless", "bpb-formless", "0.2", "formless_hooks")
    registry = make_registry([(Formless(), source)])
    session = HumanSession(data, run, "ann", registry, RunOptions(tasks=("badform",)))
    return TestClient(human_app(session), base_url="http://127.0.0.1")


def _message(page: str) -> str:
    found = re.search(r'id="error-message">(.*?)</p>', page, re.S)
    assert found is not None, page
    return html.unescape(found.group(1))


PAGE_FLAWS = [
    ("context_raise", "form_context() raised RuntimeError: context exploded"),
    ("context_type", "form_context() returned list; expected a dict of template values named "
     "by str"),
    ("context_reserved", "form_context() returned 'prefix', a value core sets itself"),
    ("template_undefined", "form_template raised UndefinedError: 'no_such_value' is undefined"),
]  # fmt: skip


@pytest.mark.parametrize(("flaw", "said"), PAGE_FLAWS)
def test_a_flawed_form_page_names_the_task_plugin(
    monkeypatch: pytest.MonkeyPatch, small_dataset: Path, tmp_path: Path, flaw: str, said: str
) -> None:
    client = _client(small_dataset, tmp_path / "run")
    assert client.get("/").status_code == 200
    monkeypatch.setattr(BadFormTask, "flaw", flaw)
    reply = client.get("/")
    assert reply.status_code == 500
    assert _message(reply.text) == f"{ORIGIN}: {TASK}: {said}"


@pytest.mark.parametrize(
    ("flaw", "said"),
    [
        ("read_raise", "read_form() raised KeyError: 'TOP'"),
        ("read_type", "read_form() returned no answer JSON can hold (a str); expected a dict in "
         "the task's answer format"),
    ],
)  # fmt: skip
def test_a_flawed_read_form_names_the_task_plugin_and_stores_nothing(
    monkeypatch: pytest.MonkeyPatch, small_dataset: Path, tmp_path: Path, flaw: str, said: str
) -> None:
    client = _client(small_dataset, tmp_path / "run")
    page = client.get("/").text
    form = dict(re.findall(r'name="(scene|shown|token)" value="([^"]+)"', page))
    form["badform.none"] = "T"  # the person says: no wall
    monkeypatch.setattr(BadFormTask, "flaw", flaw)
    reply = client.post("/answer", data=form, follow_redirects=False)
    assert reply.status_code == 500
    assert _message(reply.text) == f"{ORIGIN}: {TASK}: {said}"
    assert list(iter_answers(tmp_path / "run")) == []
    monkeypatch.setattr(BadFormTask, "flaw", "")
    assert client.post("/answer", data=form, follow_redirects=False).status_code == 303
