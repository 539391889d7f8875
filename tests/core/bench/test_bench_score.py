"""``bpb bench score``: every installed scorer on real units, one million rows within two
seconds."""

from __future__ import annotations

import random
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bpb_core.bench.score import bench_score
from bpb_core.bench.score_sample import ScoreSample, corrupt, sample_units, scored_tasks
from bpb_core.registry import Registry
from support.tiny_plugin import install_tiny


@pytest.fixture(scope="module")
def samples(tmp_path_factory: pytest.TempPathFactory) -> dict[str, ScoreSample]:
    """Units of every installed scored task, from 4 scenes per horizon of its family."""
    from bpb_core.registry import make_registry

    registry = make_registry()
    found: dict[str, ScoreSample] = {}
    for family, tasks in scored_tasks(registry).items():
        data = tmp_path_factory.mktemp("score") / family
        found |= sample_units(registry, family, tasks, data, per_horizon=4)
    return found


def test_every_installed_task_with_a_scorer_is_benchmarked(registry: Registry) -> None:
    billiards = scored_tasks(registry)["billiards"]
    assert {"q1", "q2", "q3"} <= set(billiards)  # plugins' tasks (firsthit) join them
    assert billiards == registry.tasks_for("billiards")


def test_one_million_real_units_score_within_two_seconds(samples: dict[str, ScoreSample]) -> None:
    for task, sample in samples.items():
        frame = sample.tiled(1_000_000)
        started = time.perf_counter()
        result = sample.scorer.score(frame)
        elapsed = time.perf_counter() - started
        assert elapsed < 2.0, task
        assert len(result) == 1_000_000 and str(result["correct"].dtype) == "bool"
        # oracle answers are right, predictors and failed calls mostly are not
        assert 0.3 < result["correct"].mean() < 0.95, task


def test_sample_mixes_failed_calls_missing_and_repeated_units(
    samples: dict[str, ScoreSample],
) -> None:
    for task, sample in samples.items():
        frame = sample.frame
        assert set(frame["status"]) == {"ok", "parse_error", "api_error"}, task
        if task in ("q1", "q2", "q3"):  # answers with lists of entries
            assert frame["duplicate"].any(), task  # a corrupted answer repeats an entry
            ok = frame["status"] == "ok"
            assert frame.loc[ok, "pred"].isna().any(), task  # ... or drops one
        assert len(sample.cases) == len(sample.cut())


def test_corrupt_drops_or_repeats_one_entry_of_a_copy() -> None:
    answer = {"answers": [{"id": 1}, {"id": 2}, {"id": 3}], "note": "x"}
    sizes = {len(corrupt(answer, random.Random(seed))["answers"]) for seed in range(20)}
    assert sizes == {2, 4}
    assert answer == {"answers": [{"id": 1}, {"id": 2}, {"id": 3}], "note": "x"}
    assert corrupt({"value": 3}, random.Random(0)) == {"value": 3}


def test_bench_score_times_each_task_two_ways(registry: Registry) -> None:
    timings = bench_score(5000, repeats=2, per_horizon=2, registry=registry)
    q1 = [(t.task, t.method) for t in timings if t.task == "q1"]
    assert q1 == [("q1", "vectorised"), ("q1", "answers -> units (scaled)")]
    tasks = sorted({t.task for t in timings})
    assert tasks == registry.tasks_for("billiards")
    assert len(timings) == 2 * len(tasks) and all(
        t.rows == 5000 and 0 < t.best <= t.median for t in timings
    )
    assert all(0 < (t.correct or 0) < 1 for t in timings if t.method == "vectorised")


def test_bench_score_command_prints_a_row_per_task_and_method(bench: Callable[..., Any]) -> None:
    done = bench("score", "--rows", "20000", "--repeats", "1", "--per-horizon", "2")
    assert done.returncode == 0, done.stderr
    builtins = [(r[0], r[1]) for r in done.rows if r[0] in ("q1", "q2", "q3")]
    assert builtins == [
        (task, method)
        for task in ("q1", "q2", "q3")
        for method in ("vectorised", "answers -> units (scaled)")
    ]
    for row in done.rows:
        assert row[2] == "20,000" and 0 <= float(row[3]) <= float(row[4])
        assert float(row[5].replace(",", "")) > 0


def test_bench_score_refuses_a_bad_runs_folder_before_scoring(
    tmp_path: Path, bench: Callable[..., Any]
) -> None:
    empty = tmp_path / "empty"
    empty.mkdir()
    for folder, message in [(tmp_path / "nosuch", "no such run folder"), (empty, "holds none")]:
        done = bench("score", "--per-horizon", "1", "--runs", folder)  # 1M rows x 5: minutes
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1, done.stderr
        assert lines[0].startswith(f"error: {folder}: ") and message in lines[0]
        assert done.stdout == ""  # no scoring table: refused first


def test_bench_score_covers_a_third_party_family(tmp_path: Path, bench: Callable[..., Any]) -> None:
    tiny = install_tiny(tmp_path / "site")
    done = bench("score", "--rows", "2000", "--repeats", "1", "--per-horizon", "2", env=tiny.env)
    assert done.returncode == 0, done.stderr
    tasks = {r[0] for r in done.rows}
    assert {"q1", "q2", "q3"} < tasks and len(tasks) > 3  # the plugin's task is timed too
