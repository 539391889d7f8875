"""An adapter whose preflight(), cannot_answer(), estimate() or priced raises or returns the wrong
type is one PluginBug naming its plugin (exit 3 in the CLI), before any call is sent.

Before, a raise in any of them left ``bpb run`` as "internal error: RuntimeError" naming no
plugin; a preflight() or cannot_answer() returning a list or True was shown to the user as what
to fix (exit 2, "--adapter careless:x: True"), and without --adapter such an offline adapter was
silently left out; an estimate() of text tokens was "internal error: TypeError" and a negative
one was added into the dry run's figures. A ``priced`` that raised (read by --max-cost) was a raw
"internal error: RuntimeError"; one of "yes" was taken as priced.
"""

from __future__ import annotations

import functools
import types
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bpb_core.errors import PluginBug
from bpb_core.registry import PluginSource, make_registry
from bpb_core.runner import RunOptions, run_eval
from support.inprocess import Done, bpb

ORIGIN = "plugin 'careless' (careless_hooks) from bpb-careless 0.3"
ADAPTER = "adapter 'careless:x'"
CARELESS = """
import os

from bpb_core import AdapterInfo, ModelResponse, Usage, hookimpl


def _flaw():
    return os.environ.get("BPB_TEST_FLAW", "")


class Careless:
    def __init__(self, model):
        self.name = f"careless:{model}"

    async def complete(self, request):
        return ModelResponse('{"n": 0}', Usage(), None, 0.0, "careless")

    def preflight(self):
        if _flaw() == "preflight_raise":
            raise RuntimeError("preflight exploded")
        return ["no key"] if _flaw() == "preflight_type" else None

    def cannot_answer(self, family):
        if _flaw() == "cannot_answer_raise":
            raise KeyError(family.name)
        return True if _flaw() == "cannot_answer_type" else None

    @property
    def priced(self):
        if _flaw() == "priced_raise":
            raise RuntimeError("no price list")
        return "yes" if _flaw() == "priced_type" else True

    def estimate(self, messages):
        if _flaw() == "estimate_raise":
            raise RuntimeError("estimate exploded")
        if _flaw() == "estimate_type":
            return ("12", None)
        return (-5, 0.1) if _flaw() == "estimate_negative" else (12, 0.001)


@hookimpl
def bpb_model_adapters():
    make = lambda: lambda model, options: Careless(model)
    return [AdapterInfo("careless", make, "Careless on demand", offline=True, models=("x",))]
"""
ESTIMATE = "estimate() returned {}; expected (input tokens, cost): an int at least 0 and a " \
    "finite float at least 0 or None"  # fmt: skip
FLAWS = [
    ("preflight_raise", [], "preflight() raised RuntimeError: preflight exploded"),
    ("preflight_type", [], "preflight() returned list; expected None or a str"),
    ("cannot_answer_raise", [], "cannot_answer('billiards') raised KeyError: 'billiards'"),
    ("cannot_answer_type", [], "cannot_answer('billiards') returned bool; expected None or a str"),
    ("estimate_raise", ["--dry-run"], "estimate() raised RuntimeError: estimate exploded"),
    ("estimate_type", ["--dry-run"], ESTIMATE.format("('12', None)")),
    ("estimate_negative", ["--dry-run"], ESTIMATE.format("(-5, 0.1)")),
    ("priced_raise", ["--max-cost", "1"], "priced raised RuntimeError: no price list"),
    ("priced_type", ["--max-cost", "1"], "priced is 'yes'; expected a bool"),
]


@pytest.fixture
def run_bpb(site: Path, capfd: pytest.CaptureFixture[str]) -> Callable[..., Done]:
    """``bpb ARGS`` in this process, ``site`` first on ``sys.path`` (conftest's ``run_bpb``
    runs the console script)."""
    return functools.partial(bpb, capfd, site=site)


@pytest.mark.parametrize(("flaw", "extra", "said"), FLAWS)
def test_bpb_run_is_one_line_naming_the_adapter_plugin_and_exit_3(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, dataset: Path, tmp_path: Path,
    flaw: str, extra: list[str], said: str,
) -> None:  # fmt: skip
    install("bpb-careless", "0.3", {"careless_hooks": CARELESS}, {"careless": "careless_hooks"})
    args = ["run", "--data", str(dataset), "--limit", "1", *extra]
    good = run_bpb(*args, "--out", str(tmp_path / "good"), "--adapter", "careless:x")
    assert good.returncode == 0, good.stderr
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    for adapters in (["--adapter", "careless:x"], []):  # given, or among the offline defaults
        done = run_bpb(*args, "--out", str(tmp_path / "flawed"), *adapters)
        assert done.returncode == 3, adapters
        assert done.stderr.strip().splitlines() == [
            f"error: {ORIGIN}: {ADAPTER}: {said} (set BPB_DEBUG=1 for a traceback)"
        ]
        assert not (tmp_path / "flawed").exists()  # refused before the first call


@pytest.mark.parametrize(("flaw", "extra", "said"), FLAWS[:4])
def test_run_eval_names_the_adapter_plugin(
    monkeypatch: pytest.MonkeyPatch, dataset: Path, tmp_path: Path, flaw: str, extra: list[str],
    said: str,
) -> None:  # fmt: skip
    careless_hooks = types.ModuleType("careless_hooks")
    exec(CARELESS, careless_hooks.__dict__)
    source = PluginSource("careless", "bpb-careless", "0.3", "careless_hooks")
    registry = make_registry([(careless_hooks, source)])
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    with pytest.raises(PluginBug) as info:
        run_eval(dataset, "careless:x", tmp_path / "run", RunOptions(limit=1), registry=registry)
    assert str(info.value) == f"{ORIGIN}: {ADAPTER}: {said}"
    assert not (tmp_path / "run").exists()
