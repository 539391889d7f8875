"""Ctrl-C and SIGTERM during a run: stop sending, finish writing, record why.

The first signal stops new calls; the calls in flight (already paid for) finish and are written,
and ``run.json`` records ``stopped: "interrupted"``. A second signal abandons the calls still in
flight (their pairs stay unsent and are asked again on resume).

Handlers are installed only when the run owns its event loop in the main thread (``bpb run``, a
synchronous ``run_eval``: see :func:`owning_signals`), and the process's handlers are put back
as they were when it ends. A run awaited in the caller's own loop (``run_eval_async`` in an
async app or a notebook) and a run in a worker thread leave the signals to the caller, whose
way to stop it is cancelling its task.
"""

from __future__ import annotations

import asyncio
import contextlib
import contextvars
import signal
from collections.abc import Coroutine, Iterator
from typing import Any, TypeVar

from bpb_core.runner.progress import ProgressEvent
from bpb_core.runner.state import RunState

INTERRUPTED = "interrupted"
_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_OWNS_SIGNALS = contextvars.ContextVar("bpb_owns_signals", default=False)
T = TypeVar("T")


async def owning_signals(run: Coroutine[Any, Any, T]) -> T:
    """Await ``run`` as the owner of its event loop: its runs handle SIGINT and SIGTERM (for
    the coroutine given to ``asyncio.run`` by a synchronous entry point, never a caller's)."""
    _OWNS_SIGNALS.set(True)  # in this task's own context: the caller's stays as it was
    return await run


def _on_signal(state: RunState, jobs: set[asyncio.Task[None]]) -> None:
    state.interrupts += 1
    if state.interrupts == 1:
        state.stop(INTERRUPTED)  # also wakes the calls queued for a rate-limit slot
        state.progress.update(
            ProgressEvent(
                state.spec,
                "",
                "warning",
                reason="interrupted: no new calls; finishing the calls in flight "
                "(interrupt again to abandon them)",
            )
        )
        return
    for job in list(jobs):
        job.cancel()


@contextlib.contextmanager
def interruptible(state: RunState, jobs: set[asyncio.Task[None]]) -> Iterator[None]:
    """Handle SIGINT and SIGTERM on the running loop for the block, when the run owns the loop
    (:func:`owning_signals`) and it runs in the main thread; then restore the process's own
    handlers."""
    if not _OWNS_SIGNALS.get():
        yield
        return
    loop = asyncio.get_running_loop()
    installed: dict[signal.Signals, Any] = {}
    for sig in _SIGNALS:
        before = signal.getsignal(sig)
        try:
            loop.add_signal_handler(sig, _on_signal, state, jobs)
        except (RuntimeError, NotImplementedError):  # not the main thread; no signals here
            continue
        installed[sig] = before
    try:
        yield
    finally:
        for sig, before in installed.items():
            loop.remove_signal_handler(sig)
            if before is not None:  # None: a handler not set from Python, nothing to restore
                signal.signal(sig, before)
