"""Request pacing: an optional requests-per-minute cap shared by all calls of a run."""

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
