"""Scoring speed: one million answer rows in at most two seconds per scorer."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from bpb_core.bench.score import synthetic_units
from bpb_core.registry import make_registry


@pytest.mark.parametrize("task", ["q1", "q2", "q3"])
def test_one_million_rows_score_within_two_seconds(task: str) -> None:
    registry = make_registry()
    scorer = registry.scorer(registry.scorers_for(task)[0].info.name)
    frame = synthetic_units(task, 1_000_000)
    started = time.perf_counter()
    result = scorer.score(frame)
    elapsed = time.perf_counter() - started
    assert elapsed < 2.0
    assert len(result) == 1_000_000 and str(result["correct"].dtype) == "bool"
    # the synthetic mix has roughly 10% non-ok calls, so never everything right
    assert 0.1 < result["correct"].mean() < 0.9


def test_bench_score_command_prints_the_table() -> None:
    bpb = str(Path(sys.executable).with_name("bpb"))
    args = ["bench", "score", "--rows", "20000", "--repeats", "1", "--loop-rows", "2000"]
    done = subprocess.run([bpb, *args], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "vectorised" in done.stdout and "per-row loop" in done.stdout
