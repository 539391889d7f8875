"""The library's async face: ``bpb_core.run_eval_async`` and ``evaluate_async`` for callers in an
event loop (they took only Path and returned no scores, and were not in ``bpb_core``)."""

from __future__ import annotations

import asyncio
import threading
import time
from pathlib import Path
from typing import Any

import bpb_core
from bpb_core import (
    AdapterInfo,
    EvalResult,
    ModelResponse,
    RunOptions,
    Usage,
    evaluate_async,
    hookimpl,
    leaderboard,
    run_eval_async,
)
from bpb_core.registry import Registry, make_registry


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


LOADING: dict[str, Any] = {}


class Answering:
    name = "slowsdk:x"

    async def complete(self, request: Any) -> ModelResponse:
        return ModelResponse('{"answers": []}', Usage(), None, 0.0, "slowsdk")


def _slow_sdk() -> Any:
    """A plugin's adapter whose provider SDK takes half a second to import (litellm takes
    seconds), loaded when the run builds the adapter."""
    LOADING["thread"], LOADING["start"] = threading.current_thread(), time.monotonic()
    time.sleep(0.5)
    LOADING["end"] = time.monotonic()
    return lambda model, options: Answering()


class SlowSdk:
    @hookimpl
    def bpb_model_adapters(self) -> list[AdapterInfo]:
        return [AdapterInfo("slowsdk", _slow_sdk)]


def test_the_set_up_of_run_eval_async_leaves_the_callers_loop_serving(
    dataset: Path, tmp_path: Path
) -> None:
    """The set-up (registry, adapter, dataset, run folder) ran on the caller's loop: an app's
    other tasks stood still while a plugin's adapter loaded; a heartbeat there missed every
    beat of the load. It now runs in a worker thread."""
    LOADING.clear()
    registry = make_registry([SlowSdk()])
    beats: list[float] = []

    async def app() -> tuple[EvalResult, threading.Thread]:
        async def heartbeat() -> None:
            while True:
                beats.append(time.monotonic())
                await asyncio.sleep(0.01)

        beating = asyncio.create_task(heartbeat())
        await asyncio.sleep(0)
        options = RunOptions(tasks=("q2",), limit=1)
        done = await run_eval_async(
            dataset, "slowsdk:x", tmp_path / "run", options, registry=registry
        )
        beating.cancel()
        return done, threading.current_thread()

    done, loop_thread = asyncio.run(app())
    assert set(done.scores["status"]) == {"parse_error"}  # the run itself went through
    assert LOADING["thread"] is not loop_thread
    during = [b for b in beats if LOADING["start"] < b < LOADING["end"]]
    assert len(during) >= 10  # about 50 at 10 ms; none when the load blocked the loop
