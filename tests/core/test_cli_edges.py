"""What a user meets at the edges of the command line: bare ``bpb``, and a written report
asked for without the packages that draw it."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from support.inprocess import bpb


def test_bare_bpb_prints_the_help_and_exits_0(capfd: pytest.CaptureFixture[str]) -> None:
    done = bpb(capfd)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("Usage: bpb")
    assert "generate" in done.stdout and "report" in done.stdout
    assert "error" not in done.stderr


def test_a_written_report_without_matplotlib_is_one_line_before_any_scoring(
    capfd: pytest.CaptureFixture[str], runs: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if the report extra were absent
    out = runs.parent / "report"
    done = bpb(capfd, "report", str(runs), "--out", str(out))
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "error: a written report (--out) needs matplotlib: pip install 'bpb[report]' "
        "(the terminal report and --json work without them)"
    ]
    assert not out.exists()
    terminal = bpb(capfd, "report", str(runs))  # the terminal report still works
    assert terminal.returncode == 0, terminal.stderr
    assert "oracle" in terminal.stdout
