"""Terminal tables at 80, 100 and 120 columns: every value whole, every run told apart."""

from __future__ import annotations

import functools
import io
import json
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import given, settings, strategies as st
from rich.console import Console

from bpb_core.cli.console import MIN_NAME, Name, fitted
from support import inprocess
from support.inprocess import Done

WIDTHS = (80, 100, 120)
MODELS = [
    "gpt-5.5", "gpt-5.4", "gpt-5.4-pro", "gpt-5.4-mini", "o3", "claude-opus-4.7[thinking=8000]",
    "claude-opus-4.6[thinking=8000]", "claude-opus-4.5[thinking=8000]", "claude-sonnet-4.6",
    "gemini-3.1-pro-preview", "gemini-3-flash-preview", "gemini-2.5-pro", "grok-4", "qwen3-vl-235b",
    "glm-4.6v", "kimi-k2.5", "llama-4-maverick",
]  # fmt: skip


def rendered(tables: list, width: int) -> list[list[str]]:  # type: ignore[type-arg]
    """The body rows of ``tables`` printed at ``width``, as lists of stripped cells."""
    console = Console(width=width, file=io.StringIO(), color_system=None, emoji=False)
    rows = []
    for table in tables:
        console.print(table)
    text = console.file.getvalue()  # type: ignore[attr-defined]
    assert max(map(len, text.splitlines())) <= width
    for line in text.splitlines():
        if line.startswith("│"):
            rows.append([cell.strip() for cell in line.strip("│").split("│")])
    return rows


@pytest.mark.parametrize("width", WIDTHS)
def test_a_paper_size_sweep_fits_with_every_score_whole_and_names_told_apart(width: int) -> None:
    names = [Name(f"litellm_{m}") for m in MODELS] + [
        Name(f"baseline_{b}", " (baseline)", "dim") for b in ("stasis", "straight", "random")
    ]
    head = ["run", "complete", "q1", "q2", "q3", "total", "total strict", "total 95% CI"]
    rows = [
        (name, ["100.0%", f"{50 + k}.{k}%", "12.5%", "7.25%", "88.8%", "61.0%", "59.3%–63.1%"])
        for k, name in enumerate(names)
    ]
    body = rendered(fitted("Leaderboard", head, rows, width), width)
    parts = len(body) // len(rows)
    assert parts * len(rows) == len(body)
    for p in range(parts):
        labels = [row[0] for row in body[p * len(rows) : (p + 1) * len(rows)]]
        assert len(set(labels)) == len(labels), labels  # opus 4.6 and 4.7 are not one name
    for k, (_, cells) in enumerate(rows):
        shown = [cell for p in range(parts) for cell in body[p * len(rows) + k][1:]]
        assert shown == cells  # every value whole, in order, once
    if width >= 120:
        assert parts == 1


@settings(max_examples=60, deadline=None)
@given(
    names=st.lists(st.text("ab-_.[]=0123456789", min_size=1, max_size=60), min_size=1, max_size=8),
    widths=st.lists(st.integers(1, 14), min_size=1, max_size=12),
    width=st.sampled_from(WIDTHS),
)
def test_any_names_and_columns_fit_with_values_whole(
    names: list[str], widths: list[int], width: int
) -> None:
    head = ["run", *(f"c{j}" for j in range(len(widths)))]
    rows = [(Name(n), ["9" * w for w in widths]) for n in names]
    body = rendered(fitted("t", head, rows, width), width)
    expected = sorted(["9" * w for w in widths] * len(names))
    assert sorted(c for row in body for c in row[1:]) == expected
    labels = [row[0] for row in body[: len(names)]]
    assert len(set(labels)) == len(set(names))
    assert all(len(label) >= min(MIN_NAME, len(n)) for label, n in zip(labels, names, strict=True))


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from support.reports_fixture import write_runs

    return write_runs(tmp_path_factory.mktemp("widths"))


@pytest.fixture
def bpb(capfd: pytest.CaptureFixture[str]) -> Callable[..., Done]:
    return functools.partial(inprocess.bpb, capfd)


@pytest.mark.parametrize("width", WIDTHS)
def test_bpb_report_shows_every_leaderboard_score_at_each_width(
    bpb: Callable[..., Done], runs: Path, width: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", str(width))
    summary = json.loads(bpb("report", str(runs), "--json", "--bootstrap", "50").stdout)
    done = bpb("report", str(runs), "--bootstrap", "50")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert max(map(len, lines)) <= width
    board = lines[: next(i for i, line in enumerate(lines) if "metrics beside" in line)]
    for row in summary["leaderboard"]:
        mine = " ".join(line for line in board if f"│ {row['run']} " in line)
        for task in (t for t in ("q1", "q2", "q3", "total") if row[t] is not None):
            assert f"{100 * row[task]:.1f}%" in mine, (width, row["run"], task)
        assert "…" not in mine
