"""A run called from a host program (a notebook, an async web app, a worker thread): cancelling
it, the process's signal handlers, the host's event loop."""

from __future__ import annotations

import asyncio
import contextlib
import fcntl
import json
import os
import signal
import threading
import time
from pathlib import Path

import pytest

from bpb_core.model_calls import ModelRequest, ModelResponse
from bpb_core.registry import Registry
from bpb_core.run_folder import iter_answers
from bpb_core.runner import RunOptions, run_eval
from bpb_core.runner.run import run_eval_async


class Gated:
    """The oracle's answers, each but the first held until ``release`` is set (a run sends one
    call at a time until its adapter has replied once); counts the calls started."""

    name = "fake:gated"

    def __init__(self, oracle: object) -> None:
        self.oracle = oracle
        self.started = 0
        self.two_started = asyncio.Event()
        self.release = asyncio.Event()

    async def complete(self, request: ModelRequest) -> ModelResponse:
        self.started += 1
        if self.started > 1:  # two held calls: the first reply opened --concurrency 2
            if self.started == 3:
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
    assert at_cancel == 3 and later == 3, "no call is sent after the run was cancelled"
    assert not others, f"tasks left running in the host's loop: {others}"
    assert _lock_free(run_dir)
    assert json.loads((run_dir / "run.json").read_text())["stopped"] == "interrupted"
    assert len(list(iter_answers(run_dir))) == 1  # the two calls in flight were abandoned

    again = Gated(registry.adapter("baseline:oracle"))
    again.release.set()
    done = run_eval(dataset, again, run_dir, options, registry=registry)
    assert done.stopped is None
    assert len(list(iter_answers(run_dir))) == 2 * 3 * 3


def _host_handler(signum: int, frame: object) -> None:  # pragma: no cover (never delivered)
    raise AssertionError("not called in these tests")


def test_a_synchronous_run_puts_the_callers_signal_handlers_back(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    """run_eval reset SIGINT to Python's default and SIGTERM to SIG_DFL when it returned,
    dropping the handlers the calling program had set (a server's graceful shutdown)."""
    before = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        signal.signal(signal.SIGINT, _host_handler)
        signal.signal(signal.SIGTERM, _host_handler)
        run_eval(
            dataset, "baseline:oracle", tmp_path / "run", RunOptions(limit=1), registry=registry
        )
        assert signal.getsignal(signal.SIGINT) is _host_handler
        assert signal.getsignal(signal.SIGTERM) is _host_handler
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)


def test_a_run_awaited_in_the_callers_loop_leaves_its_signal_handlers(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    """An async app's own SIGTERM handler on its loop was replaced during the run and removed
    after it (SIGTERM then killed the app); the app's SIGINT handling went the same way."""
    terms: list[str] = []

    async def app() -> tuple[object, object, object, object]:
        loop = asyncio.get_running_loop()
        loop.add_signal_handler(signal.SIGTERM, terms.append, "app")
        at_start = signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)
        try:
            await run_eval_async(
                dataset, "baseline:oracle", tmp_path / "run", RunOptions(limit=1), registry=registry
            )
            return (*at_start, signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT))
        finally:
            loop.remove_signal_handler(signal.SIGTERM)

    term_before, int_before, term_after, int_after = asyncio.run(app())
    assert term_after is term_before and term_after is not signal.SIG_DFL
    assert int_after is int_before  # asyncio.run's own Ctrl-C handler, still in place


def test_run_eval_works_inside_a_running_event_loop(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    """A notebook cell (or an async handler) calling run_eval got RuntimeError: asyncio.run()
    cannot be called from a running event loop, and a 'never awaited' warning."""

    async def cell() -> object:
        return run_eval(dataset, "baseline:oracle", tmp_path / "run", registry=registry)

    done = asyncio.run(cell())
    assert done.statuses["q1"]["ok"] == 6  # type: ignore[attr-defined]
    assert len(list(iter_answers(tmp_path / "run"))) == 2 * 3 * 3


class ThreadGated:
    """The oracle's answers, each but the first held until ``release`` is set; usable from any
    thread."""

    name = "fake:gated"

    def __init__(self, oracle: object) -> None:
        self.oracle = oracle
        self.started = 0
        self.two_started = threading.Event()
        self.release = threading.Event()

    async def complete(self, request: ModelRequest) -> ModelResponse:
        self.started += 1
        if self.started > 1:  # two held calls: the first reply opened --concurrency 2
            if self.started == 3:
                self.two_started.set()
            while not self.release.is_set():
                await asyncio.sleep(0.01)
        right: ModelResponse = await self.oracle.complete(request)  # type: ignore[attr-defined]
        return right


@pytest.mark.parametrize("host", ["notebook", "asyncio.run"])
def test_an_interrupt_of_run_eval_in_a_running_loop_stops_the_run(
    host: str, dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    """Ctrl-C during run_eval called in a running loop: a notebook kernel's loop gets
    KeyboardInterrupt, asyncio.run cancels its main task; either way the run (on its own loop
    in a helper thread) is cancelled and has ended when the caller sees it."""
    run_dir = tmp_path / "run"
    adapter = ThreadGated(registry.adapter("baseline:oracle"))

    def interrupt() -> None:
        adapter.two_started.wait(10)
        signal.pthread_kill(threading.main_thread().ident or 0, signal.SIGINT)  # Ctrl-C

    async def cell() -> None:
        run_eval(dataset, adapter, run_dir, RunOptions(concurrency=2), registry=registry)
        await asyncio.sleep(0)  # where asyncio.run's cancellation reaches the caller

    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        threading.Thread(target=interrupt).start()
        with pytest.raises(KeyboardInterrupt):
            if host == "asyncio.run":
                asyncio.run(cell())
            else:  # a kernel runs its loop itself: no handler of asyncio.run's
                loop = asyncio.new_event_loop()
                try:
                    loop.run_until_complete(cell())
                finally:
                    loop.close()
    finally:
        signal.signal(signal.SIGINT, before)
    at_interrupt = adapter.started
    adapter.release.set()
    time.sleep(0.2)
    assert adapter.started == at_interrupt == 3
    assert not [t for t in threading.enumerate() if t.name == "bpb-run"]
    assert _lock_free(run_dir)
    assert json.loads((run_dir / "run.json").read_text())["stopped"] == "interrupted"
