"""Options, progress events and results of an evaluation run."""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Protocol

from bpb_core.interfaces import InputMode


@dataclass(frozen=True)
class RetryPolicy:
    """How hard the runner tries before it records a failure.

    Attributes:
        max_retries: Extra tries after infrastructure errors (429, 5xx, timeout, connection).
        base_delay: First backoff in seconds; doubles each retry, with full jitter.
        max_delay: Cap on one backoff (and on a server's Retry-After).
        max_reasks: Re-asks after a malformed answer, each escalating the prompt.
        timeout_growth: Factor applied to the timeout after a timeout and on each re-ask.
    """

    max_retries: int = 6
    base_delay: float = 1.0
    max_delay: float = 60.0
    max_reasks: int = 2
    timeout_growth: float = 1.5


@dataclass(frozen=True)
class RunOptions:
    """Everything that shapes the calls of a run (recorded in ``run.json``).

    Attributes:
        tasks: Task names, in order.
        horizons: Horizons to include (``None`` for all).
        limit: First N scenes per horizon (``None`` for all).
        concurrency: Calls in flight at once.
        rpm: Requests-per-minute cap (``None`` for none).
        cot: Per-task chain-of-thought overrides; a task not listed uses its default.
        max_tokens: Output token cap per call.
        timeout: Seconds per call before it times out (grows on retries).
        temperature: Sampling temperature (0, as in the paper).
        force_numeric: Ask Q3 for numbers instead of null.
        input_mode: ``image``, ``image+state`` or ``state``.
        max_cost: Stop sending calls once the run has spent this many USD.
        seed: Seed for adapters with randomness.
        retry: Retry policy.
    """

    tasks: tuple[str, ...] = ("q1", "q2", "q3")
    horizons: tuple[float, ...] | None = None
    limit: int | None = None
    concurrency: int = 8
    rpm: float | None = None
    cot: Mapping[str, bool] = field(default_factory=dict)
    max_tokens: int | None = None
    timeout: float = 120.0
    temperature: float = 0.0
    force_numeric: bool = False
    input_mode: InputMode = "image"
    max_cost: float | None = None
    seed: int = 0
    retry: RetryPolicy = RetryPolicy()


EventKind = Literal["planned", "skipped", "retry", "done"]


@dataclass(frozen=True)
class ProgressEvent:
    """Something happened to one (scene, task) of one adapter.

    ``planned`` carries ``count`` calls to make; ``skipped`` ``count`` calls already complete
    from an earlier run; ``retry`` one failed attempt about to be repeated; ``done`` a final
    ``status`` with the tokens and cost of all its attempts.
    """

    adapter: str
    task: str
    kind: EventKind
    count: int = 1
    status: str | None = None
    tokens: int = 0
    cost: float | None = None
    reason: str | None = None


class Progress(Protocol):
    """Receives progress events (the CLI draws them; the library never prints)."""

    def update(self, event: ProgressEvent) -> None:
        """Handle one event; must be quick (it runs on the event loop)."""
        ...


class NoProgress:
    """Ignores every event."""

    def update(self, event: ProgressEvent) -> None:
        return None


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
