"""Synchronous entry points that work wherever they are called: a script, a worker thread, or
code already running inside an event loop (a Jupyter cell, an async web handler), where
``asyncio.run`` refuses to start.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections.abc import Callable, Coroutine
from typing import Any, TypeVar

from bpb_core.runner.interrupt import owning_signals

T = TypeVar("T")


def run_sync(make: Callable[[], Coroutine[Any, Any, T]]) -> T:
    """Run the coroutine ``make()`` to its end and return its result.

    With no event loop running in this thread it gets one of its own (``asyncio.run``) and owns
    its signals (:func:`~bpb_core.runner.interrupt.owning_signals`). Inside a running loop it
    runs on a loop of its own in a helper thread while this thread waits (the caller's loop is
    blocked meanwhile, as by any synchronous call; await ``run_eval_async`` to keep it
    serving). A ``KeyboardInterrupt`` while waiting (a notebook's interrupt), or the calling
    task being cancelled (``asyncio.run``'s Ctrl-C), cancels the run and waits for it to end
    (the folder stays resumable); the interrupt is raised, the cancellation reaches the caller
    at its next ``await``.
    """
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return asyncio.run(owning_signals(make()))
    return _in_thread(make)


def _in_thread(make: Callable[[], Coroutine[Any, Any, T]]) -> T:
    box: dict[str, Any] = {}
    started = threading.Event()

    async def main() -> T:
        box["loop"], box["task"] = asyncio.get_running_loop(), asyncio.current_task()
        started.set()
        return await make()

    def work() -> None:
        try:
            box["result"] = asyncio.run(main())
        except BaseException as exc:  # handed to the waiting thread
            box["error"] = exc
        finally:
            started.set()

    host = asyncio.current_task()  # cancelled by asyncio.run's Ctrl-C handler, for one
    cancelling = host.cancelling() if host is not None else 0
    thread = threading.Thread(target=work, name="bpb-run")
    thread.start()
    try:
        while thread.is_alive():
            thread.join(0.05)
            if host is not None and host.cancelling() > cancelling:
                _cancel(box, started)
                cancelling = host.cancelling()
    except KeyboardInterrupt:
        _cancel(box, started)
        thread.join()
        raise
    thread.join()
    if "error" in box:
        raise box["error"]
    result: T = box["result"]
    return result


def _cancel(box: dict[str, Any], started: threading.Event) -> None:
    """Cancel the run on the helper thread's loop (no-op once it has ended)."""
    started.wait()
    if "task" in box:
        with contextlib.suppress(RuntimeError):  # the loop has closed: the run has ended
            box["loop"].call_soon_threadsafe(box["task"].cancel)
