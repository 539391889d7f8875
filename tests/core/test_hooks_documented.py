"""Every hook is documented in the code and in docs/plugins.md, and exercised by a built-in."""

from __future__ import annotations

import inspect
from pathlib import Path

from bpb_core import hookspecs, make_registry

DOCS = Path(__file__).resolve().parents[2] / "docs" / "plugins.md"


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


def test_every_registered_builtin_loads() -> None:
    registry = make_registry()
    for entry in registry:
        assert entry.info.load() is not None, entry.info.name
        assert entry.info.summary, f"{entry.info.name} has no summary"
