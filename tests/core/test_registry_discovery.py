"""Plugin discovery through real entry points: third-party plugins, broken ones, clashes."""

from __future__ import annotations

import asyncio
import functools
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bpb_core import AdapterInfo, hookimpl, lazy, make_registry
from bpb_core.errors import PluginBug, PluginError, UnknownName
from bpb_core.model_calls import Message, ModelRequest, TextPart
from bpb_core.registry import PluginSource, PluginWarning
from support.inprocess import Done, bpb

GOOD_PLUGIN = """
from bpb_core import AdapterInfo, hookimpl, lazy

@hookimpl
def bpb_model_adapters():
    yield AdapterInfo("shout", lazy("shout_impl:make"), "Shouts", models=("loud",))
"""
GOOD_IMPL = """
import sys
sys.modules.setdefault("shout_impl_loaded", sys)

class Shout:
    def __init__(self, model):
        self.name = f"shout:{model}"

    async def complete(self, request):
        from bpb_core import ModelResponse, Usage
        text = " ".join(getattr(p, "text", "") for p in request.messages[-1].parts)
        return ModelResponse(text=text.upper(), usage=Usage(0, 0))


def make(model, options):
    return Shout(model)
"""


@pytest.fixture
def run_bpb(site: Path, capfd: pytest.CaptureFixture[str]) -> Callable[..., Done]:
    """``bpb ARGS`` in this process, ``site`` first on ``sys.path`` (conftest's ``run_bpb``
    runs the console script)."""
    return functools.partial(bpb, capfd, site=site)


def test_installed_plugin_is_listed_with_distribution_and_version(
    install: Any, run_bpb: Any
) -> None:
    install(
        "bpb-shout",
        "2.3.1",
        {"shout_hooks": GOOD_PLUGIN, "shout_impl": GOOD_IMPL},
        {"shout": "shout_hooks"},
    )
    result = run_bpb("plugins", "--json")
    assert result.returncode == 0, result.stderr
    rows = {(r["kind"], r["name"]): r for r in json.loads(result.stdout)}
    shout = rows[("adapter", "shout")]
    assert (shout["distribution"], shout["version"], shout["models"]) == (
        "bpb-shout",
        "2.3.1",
        ["loud"],
    )
    assert rows[("adapter", "baseline")]["distribution"] == "bpb"


def test_builtins_are_found_through_our_own_entry_points() -> None:
    registry = make_registry()
    baseline = registry.get("adapter", "baseline")
    assert baseline.distribution == "bpb"
    assert baseline.plugin == "baseline"


def test_load_is_lazy_until_the_component_is_used(
    install: Any, site: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    install(
        "bpb-shout",
        "1.0",
        {"shout_hooks": GOOD_PLUGIN, "shout_impl": GOOD_IMPL},
        {"shout": "shout_hooks"},
    )
    monkeypatch.syspath_prepend(str(site))
    registry = make_registry()
    assert "shout_impl" not in sys.modules
    shout = registry.adapter("shout:loud")
    assert shout.name == "shout:loud" and "shout_impl" in sys.modules
    reply = asyncio.run(
        shout.complete(ModelRequest((Message("user", (TextPart("hi there"),)),), "q1"))
    )
    assert reply.text == "HI THERE"
    for name in ("shout_hooks", "shout_impl", "shout_impl_loaded"):
        sys.modules.pop(name, None)


def test_broken_plugin_warns_and_the_rest_keeps_working(install: Any, run_bpb: Any) -> None:
    install(
        "bpb-broken",
        "0.1",
        {"broken_hooks": "import does_not_exist_anywhere\n"},
        {"broken": "broken_hooks"},
    )
    result = run_bpb("plugins", "--json")
    assert result.returncode == 0
    assert "bpb-broken" in result.stderr and "failed to import" in result.stderr
    assert "does_not_exist_anywhere" in result.stderr
    names = {r["name"] for r in json.loads(result.stdout)}
    assert "baseline" in names


def test_a_hook_that_raises_is_a_warning(recwarn: pytest.WarningsRecorder) -> None:
    class Exploding:
        @hookimpl
        def bpb_eval_tasks(self) -> Any:
            raise RuntimeError("boom")

    registry = make_registry([Exploding()], entry_points=False)
    assert registry.names("task") == []
    assert any("boom" in line for line in registry.warnings)
    assert any(issubclass(w.category, PluginWarning) for w in recwarn.list)
    recwarn.clear()
    quiet = make_registry([Exploding()], entry_points=False, warn=False)  # the caller shows them
    assert quiet.warnings == registry.warnings
    assert not any(issubclass(w.category, PluginWarning) for w in recwarn.list)


def test_name_clash_is_an_error_naming_both_distributions(install: Any, run_bpb: Any) -> None:
    clash = """
from bpb_core import AdapterInfo, hookimpl, lazy

@hookimpl
def bpb_model_adapters():
    yield AdapterInfo("baseline", lazy("os:getcwd"), "Impostor")
"""
    install("bpb-impostor", "9.9", {"impostor_hooks": clash}, {"impostor": "impostor_hooks"})
    result = run_bpb("plugins")
    assert result.returncode == 2
    line = result.stderr.strip()
    assert len(line.splitlines()) == 1
    assert "baseline" in line and "bpb-impostor" in line and "bpb " in line + " "


def test_misspelt_hook_is_caught() -> None:
    class Misspelt:
        @hookimpl
        def bpb_adapter(self) -> list[AdapterInfo]:  # missing the final s
            return []

    with pytest.raises(PluginError, match="bpb_adapter"):
        make_registry([Misspelt()], entry_points=False)


def test_record_of_the_wrong_kind_is_rejected() -> None:
    class Wrong:
        @hookimpl
        def bpb_eval_tasks(self) -> list[AdapterInfo]:
            return [AdapterInfo("x", lazy("os:getcwd"))]

    with pytest.raises(PluginError, match="expected a task record"):
        make_registry([(Wrong(), PluginSource("wrong", "bpb-wrong", "1"))], entry_points=False)


def test_unknown_name_lists_the_known_ones() -> None:
    registry = make_registry()
    with pytest.raises(UnknownName) as info:
        registry.adapter("nosuch:model")
    message = str(info.value)
    assert "nosuch" in message and "baseline" in message


def test_fresh_registries_do_not_share_state() -> None:
    class Extra:
        @hookimpl
        def bpb_model_adapters(self) -> list[AdapterInfo]:
            return [AdapterInfo("extra", lazy("os:getcwd"))]

    with_extra = make_registry([Extra()], entry_points=False)
    plain = make_registry(entry_points=False)
    assert with_extra.names("adapter") == ["extra"]
    assert plain.names("adapter") == []


FAULTY = PluginSource("faulty", "bpb-faulty", "1.2", "faulty_hooks")


def test_misspelt_hook_names_the_plugin_module_and_distribution() -> None:
    class Misspelt:
        @hookimpl
        def bpb_eval_task(self) -> list[AdapterInfo]:  # missing the final s
            return []

    with pytest.raises(PluginError) as info:
        make_registry([(Misspelt(), FAULTY)], entry_points=False)
    assert str(info.value).startswith(
        "plugin 'faulty' (faulty_hooks) from bpb-faulty 1.2: unknown hook 'bpb_eval_task'"
    )
    assert "<" not in str(info.value)  # no object reprs


def test_a_hook_returning_one_record_instead_of_an_iterable_is_an_error() -> None:
    class Bare:
        @hookimpl
        def bpb_model_adapters(self) -> AdapterInfo:
            return AdapterInfo("bare", lazy("os:getcwd"))

    with pytest.raises(PluginError, match=r"'faulty' .*returned one AdapterInfo; yield"):
        make_registry([(Bare(), FAULTY)], entry_points=False)


def test_plugin_code_failing_to_load_or_build_names_the_plugin() -> None:
    from bpb_core import TaskInfo
    from bpb_core.errors import BadInput

    def factory(model: str, options: object) -> object:
        if model == "unknown":
            raise BadInput("--adapter bad:unknown: no such model")
        raise ValueError("factory exploded")

    class Faulty:
        @hookimpl
        def bpb_eval_tasks(self) -> list[TaskInfo]:
            return [TaskInfo("nope", lazy("os.path:no_such_attribute"), family="billiards")]

        @hookimpl
        def bpb_model_adapters(self) -> list[AdapterInfo]:
            return [AdapterInfo("bad", lambda: factory)]

    registry = make_registry([(Faulty(), FAULTY)], entry_points=False)
    origin = "plugin 'faulty' (faulty_hooks) from bpb-faulty 1.2"
    with pytest.raises(PluginBug) as info:
        registry.task("nope")
    assert str(info.value) == (
        f"{origin}: loading the task 'nope' raised AttributeError: "
        "module 'posixpath' has no attribute 'no_such_attribute'"
    )
    with pytest.raises(PluginBug) as info:
        registry.adapter("bad:x")
    assert str(info.value) == (
        f"{origin}: the adapter factory for 'bad:x' raised ValueError: factory exploded"
    )
    with pytest.raises(BadInput, match="no such model"):  # bpb's own errors pass through
        registry.adapter("bad:unknown")


def test_two_scorers_for_one_task_is_an_error_naming_both_plugins() -> None:
    """Before, the alphabetically first scorer silently scored the task."""
    from bpb_core import ScorerInfo

    class Mine:
        @hookimpl
        def bpb_scorers(self) -> list[ScorerInfo]:
            return [ScorerInfo("pocketed", lazy("os:getcwd"), task="pocketed")]

    class Rival:
        @hookimpl
        def bpb_scorers(self) -> list[ScorerInfo]:
            return [ScorerInfo("a_pocketed", lazy("os:getcwd"), task="pocketed")]

    rival = PluginSource("rival", "bpb-rival", "2.0", "rival_hooks")
    with pytest.raises(PluginError) as info:
        make_registry([(Mine(), FAULTY), (Rival(), rival)], entry_points=False)
    assert str(info.value) == (
        "two scorers score the task 'pocketed': 'a_pocketed' of plugin 'rival' (rival_hooks) "
        "from bpb-rival 2.0 and 'pocketed' of plugin 'faulty' (faulty_hooks) from bpb-faulty 1.2"
    )
    assert info.value.exit_code == 2
