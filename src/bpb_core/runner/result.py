"""What a finished (or stopped) evaluation run did."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class RunResult:
    """What a finished (or stopped) run did.

    Attributes:
        run_dir: The run folder.
        adapter: Adapter spec.
        statuses: Per task, how many (scene, task) pairs ended ok / parse_error / api_error,
            plus ``done_before`` (complete from an earlier run) and ``not_sent``.
        cost: USD spent in this invocation (``None`` if any reply had no price).
        tokens: Input + output tokens in this invocation.
        stopped: Why the run stopped early (``max-cost``, ``auth``), or ``None``.
        error: The authentication error message when ``stopped`` is ``auth``.
    """

    run_dir: Path
    adapter: str
    statuses: dict[str, Counter[str]] = field(default_factory=dict)
    cost: float | None = 0.0
    tokens: int = 0
    stopped: str | None = None
    error: str | None = None

    @property
    def api_errors(self) -> int:
        """Pairs that ended with an infrastructure error (resumable)."""
        return sum(c["api_error"] for c in self.statuses.values())

    @property
    def not_sent(self) -> int:
        """Pairs never sent (stopped by the cost cap or an auth failure)."""
        return sum(c["not_sent"] for c in self.statuses.values())
