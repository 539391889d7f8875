"""The library's async face: ``bpb_core.run_eval_async`` and ``evaluate_async`` for callers in an
event loop (they took only Path and returned no scores, and were not in ``bpb_core``)."""

from __future__ import annotations

import asyncio
from pathlib import Path

import bpb_core
from bpb_core import EvalResult, RunOptions, evaluate_async, leaderboard, run_eval_async
from bpb_core.registry import Registry


def test_run_eval_async_takes_str_paths_and_returns_scores(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    async def app() -> tuple[EvalResult, list[EvalResult]]:
        one = await run_eval_async(
            str(dataset),
            "baseline:oracle",
            str(tmp_path / "one"),
            RunOptions(limit=1),
            registry=registry,
        )
        both = await evaluate_async(
            str(dataset),
            ["baseline:oracle", "baseline:stasis"],
            str(tmp_path / "runs"),
            RunOptions(limit=1),
            registry=registry,
        )
        return one, both

    one, both = asyncio.run(app())
    assert isinstance(one, EvalResult) and bool(one.scores["correct"].all())
    assert [r.run_dir.name for r in both] == ["baseline_oracle", "baseline_stasis"]
    assert list(leaderboard(both)["adapter"]) == ["baseline:oracle", "baseline:stasis"]
    assert {"run_eval_async", "evaluate_async"} <= set(bpb_core.__all__)


def test_evaluate_takes_one_adapter_alone(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    """evaluate(data, "baseline:oracle", out) read the spec letter by letter and failed with
    "--adapter 'b': expected NAME:MODEL"."""
    (one,) = bpb_core.evaluate(
        str(dataset), "baseline:oracle", tmp_path / "runs", RunOptions(limit=1), registry=registry
    )
    assert one.run_dir.name == "baseline_oracle" and bool(one.scores["correct"].all())
