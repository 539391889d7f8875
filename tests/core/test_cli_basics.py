"""The CLI surface every user meets first: help, version, listings, exit codes."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from bpb_core import __version__

BPB = str(Path(sys.executable).with_name("bpb"))


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([BPB, *args], capture_output=True, text=True, timeout=120)


def test_help_lists_commands() -> None:
    result = run("--help")
    assert result.returncode == 0
    for command in ("plugins", "list", "bench"):
        assert command in result.stdout


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
