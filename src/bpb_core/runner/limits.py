"""Request pacing: optional requests-per-minute and tokens-per-minute caps shared by all calls
of a run.

Every wait takes the run's ``stop`` event and returns early once it is set (Ctrl-C, SIGTERM,
``--max-cost``, an authentication failure): a call queued for a slot minutes ahead must not hold
the run open after it has stopped sending.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import Awaitable


async def sleep_unless(stop: asyncio.Event | None, seconds: float) -> None:
    """Sleep ``seconds``, or until ``stop`` is set if that comes first."""
    if stop is None:
        await asyncio.sleep(seconds)
        return
    with contextlib.suppress(TimeoutError):
        await asyncio.wait_for(stop.wait(), seconds)


async def wait_unless(stop: asyncio.Event | None, waiting: Awaitable[object]) -> None:
    """Await ``waiting``, or until ``stop`` is set if that comes first (``waiting`` is then
    cancelled)."""
    if stop is None:
        await waiting
        return
    task = asyncio.ensure_future(waiting)
    stopper = asyncio.ensure_future(stop.wait())
    try:
        done, _ = await asyncio.wait({task, stopper}, return_when=asyncio.FIRST_COMPLETED)
    finally:
        task.cancel()
        stopper.cancel()
    if task in done:
        task.result()


class RateLimiter:
    """Spaces call starts at least ``60 / rpm`` seconds apart (no cap when ``rpm`` is None).

    Waiting callers queue in order; the lock is held only while computing the next slot, so a
    waiting call does not block calls already allowed to go.
    """

    def __init__(self, rpm: float | None) -> None:
        self._interval = 0.0 if not rpm else 60.0 / rpm
        self._next = 0.0
        self._lock = asyncio.Lock()

    async def wait(self, stop: asyncio.Event | None = None) -> None:
        """Return when the next call may start (or once ``stop`` is set)."""
        if self._interval <= 0:
            return
        async with self._lock:
            now = time.monotonic()
            start = max(now, self._next)
            self._next = start + self._interval
        delay = start - now
        if delay > 0:
            await sleep_unless(stop, delay)


class TokenBudget:
    """A tokens-per-minute cap (aiolimiter's leaky bucket; no cap when ``tpm`` is None).

    A call's tokens are known only after its reply, so each call first draws the running mean
    of the tokens replies have used so far (the first call draws nothing); over a run the draws
    add up to the tokens spent.
    """

    def __init__(self, tpm: float | None) -> None:
        from aiolimiter import AsyncLimiter

        self._cap = tpm
        self._bucket = None if not tpm else AsyncLimiter(tpm, 60.0)
        self._replies = 0
        self._tokens = 0

    async def wait(self, stop: asyncio.Event | None = None) -> None:
        """Return when the next call's expected tokens fit the budget (or once ``stop`` is
        set)."""
        if self._bucket is None or self._cap is None or not self._replies:
            return
        await wait_unless(stop, self._bucket.acquire(min(self._tokens / self._replies, self._cap)))

    def spent(self, tokens: int) -> None:
        """Record the tokens one reply used (input plus output)."""
        self._replies += 1
        self._tokens += tokens
