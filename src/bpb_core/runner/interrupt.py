"""Ctrl-C and SIGTERM during a run: stop sending, finish writing, record why.

The first signal stops new calls; the calls in flight (already paid for) finish and are written,
and ``run.json`` records ``stopped: "interrupted"``. A second signal abandons the calls still in
flight (their pairs stay unsent and are asked again on resume). Handlers are installed only when
the run owns the main thread's event loop; library callers in other threads keep their own.
"""

from __future__ import annotations

import asyncio
import contextlib
import signal
from collections.abc import Iterator

from bpb_core.runner.progress import ProgressEvent
from bpb_core.runner.state import RunState

INTERRUPTED = "interrupted"
_SIGNALS = (signal.SIGINT, signal.SIGTERM)


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
    """Handle SIGINT and SIGTERM on the running loop for the block (when it can)."""
    loop = asyncio.get_running_loop()
    installed = []
    for sig in _SIGNALS:
        try:
            loop.add_signal_handler(sig, _on_signal, state, jobs)
        except (RuntimeError, NotImplementedError):  # not the main thread; no signals here
            continue
        installed.append(sig)
    try:
        yield
    finally:
        for sig in installed:
            loop.remove_signal_handler(sig)
