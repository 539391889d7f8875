"""Request pacing: optional requests-per-minute and tokens-per-minute caps shared by all calls
of a run."""

from __future__ import annotations

import asyncio
import time


class RateLimiter:
    """Spaces call starts at least ``60 / rpm`` seconds apart (no cap when ``rpm`` is None).

    Waiting callers queue in order; the lock is held only while computing the next slot, so a
    waiting call does not block calls already allowed to go.
    """

    def __init__(self, rpm: float | None) -> None:
        self._interval = 0.0 if not rpm else 60.0 / rpm
        self._next = 0.0
        self._lock = asyncio.Lock()

    async def wait(self) -> None:
        """Return when the next call may start."""
        if self._interval <= 0:
            return
        async with self._lock:
            now = time.monotonic()
            start = max(now, self._next)
            self._next = start + self._interval
        delay = start - now
        if delay > 0:
            await asyncio.sleep(delay)


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

    async def wait(self) -> None:
        """Return when the next call's expected tokens fit the budget."""
        if self._bucket is None or self._cap is None or not self._replies:
            return
        await self._bucket.acquire(min(self._tokens / self._replies, self._cap))

    def spent(self, tokens: int) -> None:
        """Record the tokens one reply used (input plus output)."""
        self._replies += 1
        self._tokens += tokens
