"""Under ``bpb run``'s leaderboard, a footnote says what the columns mean and what each offline
reference answers, so "stasis scores high on Q1" reads as a floor, not a finding."""

from __future__ import annotations

from pathlib import Path

import pytest

from support.inprocess import bpb


def test_the_leaderboard_explains_its_columns_and_the_baselines(
    capfd: pytest.CaptureFixture[str], dataset: Path, tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    monkeypatch.setenv("COLUMNS", "200")
    done = bpb(capfd, "run", "--data", str(dataset), "--out", str(tmp_path / "runs"))
    assert done.returncode == 0, done.stderr
    text = " ".join(done.stdout.split())
    table_end = text.index("complete: share of the run's (scene, task) pairs answered")
    assert "baseline:stasis" in text[:table_end]  # the footnote follows the table
    assert "in brackets the strict score, where an unanswered pair counts as wrong" in text
    assert "left out: tasks under 90% answered" in text
    assert "stasis says nothing happens" in text and "oracle answers the ground truth" in text
