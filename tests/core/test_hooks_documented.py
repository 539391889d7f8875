"""Every hook is documented in the code and in docs/plugins.md, and exercised by a built-in."""

from __future__ import annotations

import inspect

from bpb_core import hookspecs
from bpb_core.registry import ReferenceInfo, Registry, SuiteInfo
from support.paths import DOCS as DOCS_DIR

DOCS = DOCS_DIR / "plugins.md"


def _hook_names() -> list[str]:
    return [n for n, f in inspect.getmembers(hookspecs, inspect.isfunction) if n.startswith("bpb_")]


def test_every_hookspec_has_a_docstring_with_returns() -> None:
    names = _hook_names()
    assert set(names) == set(hookspecs.HOOK_KINDS)
    for name in names:
        doc = inspect.getdoc(getattr(hookspecs, name)) or ""
        assert "Returns:" in doc, name


def test_every_hook_is_described_in_the_plugin_guide() -> None:
    text = DOCS.read_text()
    for name in _hook_names():
        assert f"`{name}`" in text, f"{name} missing from docs/plugins.md"


def test_every_registered_builtin_loads(registry: Registry) -> None:
    kinds = set()
    for entry in registry:
        kinds.add(entry.info.kind)
        assert entry.info.summary, f"{entry.info.name} has no summary"
        if isinstance(entry.info, SuiteInfo):  # a suite is its weights; nothing to load
            assert set(entry.info.weights) <= set(registry.names("task"))
            continue
        if isinstance(entry.info, ReferenceInfo):  # its figures; each of a task or a suite
            known = {*registry.names("task"), *registry.names("suite")}
            assert entry.info.figures and {f.metric for f in entry.info.figures} <= known
            assert all(0 <= f.value <= 1 for f in entry.info.figures)
            continue
        assert entry.info.load() is not None, entry.info.name
    assert kinds == set(hookspecs.HOOK_KINDS.values())  # every hook is used by a built-in


def test_the_guide_names_every_method_a_billiards_question_must_write() -> None:
    """A plugin author subclassing BilliardsQuestion from section 5 alone must learn every
    abstract method (the guide once named only "its question and its JSON example")."""
    from bpb_tasks.questions.question import BilliardsQuestion

    text = " ".join(DOCS.read_text().split())
    required = sorted(BilliardsQuestion.__abstractmethods__)
    assert required == ["example", "expected", "question", "validate"]
    for name in required:
        signature = inspect.signature(getattr(BilliardsQuestion, name))
        params = ", ".join(p for p in signature.parameters if p != "self")
        assert f"`{name}({params})`" in text, f"{name}({params}) missing from docs/plugins.md"
