"""The CLI surface every user meets first: help, version, listings, exit codes."""

from __future__ import annotations

import gc
import os
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import pytest

from bpb_core import __version__

BPB = str(Path(sys.executable).with_name("bpb"))


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([BPB, *args], capture_output=True, text=True, timeout=120)


def test_help_lists_commands() -> None:
    result = run("--help")
    assert result.returncode == 0
    for command in ("plugins", "list", "bench"):
        assert command in result.stdout
    # A dataset's truth may come from a stepped simulator (pymunk): the tool as a whole does not
    # promise exact physics, only the analytic simulator does.
    assert "exact physics" not in " ".join(result.stdout.split())


def test_version() -> None:
    result = run("--version")
    assert result.returncode == 0 and __version__ in result.stdout


def test_list_adapters_shows_stasis() -> None:
    result = run("list", "adapters")
    assert result.returncode == 0
    assert "baseline:stasis" in result.stdout


def test_unknown_command_is_a_usage_error() -> None:
    result = run("frobnicate")
    assert result.returncode == 2
    assert "frobnicate" in result.stderr


def test_bad_list_kind_is_a_usage_error() -> None:
    result = run("list", "gizmos")
    assert result.returncode == 2


BUGGY_PLUGIN = """
from bpb_core import AdapterInfo, hookimpl, lazy

@hookimpl
def bpb_model_adapters():
    yield AdapterInfo("buggy", lazy("buggy_impl:make"), "Crashes when built")
"""
BUGGY_IMPL = """
def make(model, options):
    raise RuntimeError("the plugin's own bug")
"""


def test_a_plugin_bug_is_one_line_naming_the_plugin_and_exit_3(
    install: Any, run_bpb: Any, dataset: Path, tmp_path: Path
) -> None:
    install("bpb-buggy", "0.1", {"buggy_hooks": BUGGY_PLUGIN, "buggy_impl": BUGGY_IMPL},
            {"buggy": "buggy_hooks"})  # fmt: skip
    done = run_bpb("run", "--data", str(dataset), "--adapter", "buggy:x", "--out", str(tmp_path))
    assert done.returncode == 3
    lines = done.stderr.strip().splitlines()
    assert lines == [
        "error: plugin 'buggy' (buggy_hooks) from bpb-buggy 0.1: the adapter factory for "
        "'buggy:x' raised RuntimeError: the plugin's own bug (set BPB_DEBUG=1 for a traceback)"
    ]


def test_list_shows_every_kind_of_component() -> None:
    suites = run("list", "suites")
    assert suites.returncode == 0
    assert suites.stdout.startswith("total\tThe paper's total score: 0.3 Q1 + 0.3 Q2 + 0.4 Q3")
    diagnostics = {line.split("\t")[0] for line in run("list", "diagnostics").stdout.split("\n")}
    assert {"q1_confusion", "q2_confusion", "stasis", "q3_tolerance"} <= diagnostics
    families = run("list", "scene-families").stdout
    assert families.startswith("billiards\t")


def _process_state() -> tuple[object, ...]:
    return warnings.showwarning, list(warnings.filters), dict(os.environ), gc.get_freeze_count()


def test_main_leaves_its_callers_process_as_it_found_it(tmp_path: Path) -> None:
    """A library caller or a test runs main() in its own process: no warning display wrapped
    once more per call, no variable left in its environment, no objects frozen."""
    from bpb_core.cli.main import main

    before = _process_state()
    generate = ["generate", "--out", str(tmp_path / "ds"), "--per-horizon", "1", "--horizons",
                "1", "--no-images", "--workers", "1"]  # fmt: skip
    for argv in (["plugins"], generate):
        with pytest.raises(SystemExit) as done:
            main(argv)
        assert done.value.code == 0
        assert _process_state() == before
    assert (tmp_path / "ds" / "dataset.json").is_file()


AT_EXIT = """
import atexit, gc, sys
atexit.register(lambda: print("frozen at exit:", gc.get_freeze_count()))  # runs last
from bpb_core.cli.main import main
try:
    main(["plugins"])
except SystemExit:
    pass
"""


def test_main_freezes_nothing_as_its_caller_exits() -> None:
    done = subprocess.run(
        [sys.executable, "-c", AT_EXIT], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "frozen at exit: 0"


FAILING_ADAPTER = """
from bpb_core import AdapterInfo, hookimpl, lazy
from bpb_core.errors import ServerError

class Down:
    name = "down:x"

    async def complete(self, request):
        raise ServerError("503")

@hookimpl
def bpb_model_adapters():
    yield AdapterInfo("down", lambda: lambda model, options: Down(), "Always 503", models=("x",))
"""


def test_an_adapter_spec_is_never_read_as_an_emoji_code(
    install: Any, run_bpb: Any, dataset: Path, tmp_path: Path
) -> None:
    install("bpb-down", "0.1", {"down_hooks": FAILING_ADAPTER}, {"down": "down_hooks"})
    out = str(tmp_path / "runs")
    done = run_bpb(
        "run", "--data", str(dataset), "--adapter", "down:x", "--tasks", "q2", "--limit", "1",
        "--retries", "0", "--out", out,
    )  # fmt: skip
    assert done.returncode == 1, done.stderr
    assert "down:x: 2 api errors" in done.stderr  # rich turned ":x:" into an emoji
    assert "\u274c" not in done.stderr + done.stdout
