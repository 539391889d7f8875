"""A run called from a host program (a notebook, an async web app, a worker thread): cancelling
it, the process's signal handlers, the host's event loop."""

from __future__ import annotations

import asyncio
import contextlib
import fcntl
import json
import os
from pathlib import Path

from bpb_core.model_calls import ModelRequest, ModelResponse
from bpb_core.registry import Registry
from bpb_core.run_folder import iter_answers
from bpb_core.runner import RunOptions, run_eval
from bpb_core.runner.run import run_eval_async


class Gated:
    """The oracle's answers, each held until ``release`` is set; counts the calls started."""

    name = "fake:gated"

    def __init__(self, oracle: object) -> None:
        self.oracle = oracle
        self.started = 0
        self.two_started = asyncio.Event()
        self.release = asyncio.Event()

    async def complete(self, request: ModelRequest) -> ModelResponse:
        self.started += 1
        if self.started >= 2:
            self.two_started.set()
        await self.release.wait()
        right: ModelResponse = await self.oracle.complete(request)  # type: ignore[attr-defined]
        return right


def _lock_free(run_dir: Path) -> bool:
    handle = os.open(run_dir / "run.lock", os.O_RDWR)
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    finally:
        os.close(handle)
    return True


def test_a_cancelled_run_stops_its_calls_and_resumes(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    """task.cancel() on a library run (a web request dropped, a notebook cell stopped) used to
    leave its calls running in the host's loop after the lock was released: they kept asking
    the model, and paid for replies no file recorded."""
    run_dir = tmp_path / "run"
    adapter = Gated(registry.adapter("baseline:oracle"))
    options = RunOptions(concurrency=2)

    async def host() -> tuple[int, int, set[asyncio.Task[object]]]:
        run = asyncio.create_task(
            run_eval_async(dataset, adapter, run_dir, options, registry=registry)
        )
        await adapter.two_started.wait()
        run.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await run
        at_cancel = adapter.started
        adapter.release.set()  # any call still alive would now reply and ask for more
        for _ in range(20):
            await asyncio.sleep(0.01)
        others = asyncio.all_tasks() - {asyncio.current_task()}  # type: ignore[operator]
        return at_cancel, adapter.started, others

    at_cancel, later, others = asyncio.run(host())
    assert at_cancel == 2 and later == 2, "no call is sent after the run was cancelled"
    assert not others, f"tasks left running in the host's loop: {others}"
    assert _lock_free(run_dir)
    assert json.loads((run_dir / "run.json").read_text())["stopped"] == "interrupted"
    assert not list(iter_answers(run_dir))  # the two calls in flight were abandoned

    again = Gated(registry.adapter("baseline:oracle"))
    again.release.set()
    done = run_eval(dataset, again, run_dir, options, registry=registry)
    assert done.stopped is None
    assert len(list(iter_answers(run_dir))) == 2 * 3 * 3
