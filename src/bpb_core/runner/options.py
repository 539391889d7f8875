"""The values a run takes and gives: its options (what is asked, how, and how hard bpb tries),
the progress events it reports while it runs, and what it did (:class:`RunResult`)."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Protocol, get_args

from bpb_core.errors import BadInput
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
        max_transport_failures: Connection failures in a row (refused, DNS, TLS) after which
            the adapter stops: the provider cannot be reached.
        transport_window: Seconds of connection failures with no reply between after which the
            adapter stops, however few they were.
    """

    max_retries: int = 6
    base_delay: float = 1.0
    max_delay: float = 60.0
    max_reasks: int = 2
    timeout_growth: float = 1.5
    max_transport_failures: int = 5
    transport_window: float = 30.0


@dataclass(frozen=True)
class RunOptions:
    """Everything that shapes the calls of a run (recorded in ``run.json``).

    Attributes:
        tasks: Task names, in order (empty: the default tasks of the dataset's scene family).
        horizons: Horizons to include (``None`` for all).
        limit: First N scenes per horizon (``None`` for all).
        concurrency: Calls in flight at once.
        rpm: Requests-per-minute cap (``None`` for none).
        tpm: Tokens-per-minute cap, input plus output (``None`` for none).
        cot: Per-task chain-of-thought overrides; a task not listed uses its default.
        max_tokens: Output token cap per call.
        timeout: Seconds per call before it times out (grows on retries).
        temperature: Sampling temperature (0, as in the paper).
        force_numeric: Ask for numbers where a task would otherwise allow null.
        input_mode: ``image``, ``image+state`` or ``state``.
        max_cost: The most USD the run folder may spend over all its sessions: each call's
            worst case is reserved before it is sent (:mod:`bpb_core.runner.budget`).
        seed: Seed for adapters with randomness, for the call order and for ``sample``.
        retry: Retry policy.
        scenes: Only these scene ids (``None`` for all selected by ``horizons``/``limit``).
        sample: A seeded random sample of this many of the selected scenes (``None``: all).
        epochs: Samples per (scene, task): each is asked ``epochs`` times, stored apart.
        structured_output: Offer each task's answer JSON Schema to the provider (off by
            default: the paper did not use it).
    """

    tasks: tuple[str, ...] = ()
    horizons: tuple[float, ...] | None = None
    limit: int | None = None
    concurrency: int = 8
    rpm: float | None = None
    tpm: float | None = None
    cot: Mapping[str, bool] = field(default_factory=dict)
    max_tokens: int | None = None
    timeout: float = 120.0
    temperature: float = 0.0
    force_numeric: bool = False
    input_mode: InputMode = "image"
    max_cost: float | None = None
    seed: int = 0
    retry: RetryPolicy = RetryPolicy()
    scenes: tuple[str, ...] | None = None
    sample: int | None = None
    epochs: int = 1
    structured_output: bool = False


def _number(option: str, value: float | None, *, zero: bool = False) -> None:
    if value is None:
        return
    low_ok = value >= 0 if zero else value > 0
    if isinstance(value, bool) or not (math.isfinite(value) and low_ok):
        need = "zero or a positive" if zero else "a positive"
        raise BadInput(f"{option}: must be {need} finite number, got {value!r}")


def check_input_mode(mode: object) -> None:
    """Refuse an input mode no task knows (the command line offers only the known ones).

    Raises:
        BadInput: One line naming the modes.
    """
    modes = get_args(InputMode)
    if mode not in modes:
        raise BadInput(f"--input-mode: must be one of {', '.join(modes)}, got {mode!r}")


def check_options(options: RunOptions) -> None:
    """Refuse options no run can use (library callers get the command line's checks).

    Raises:
        BadInput: One line naming the option: a count below 1, a non-finite or non-positive
            number.
    """
    for option, count in (
        ("--concurrency", options.concurrency),
        ("--limit", options.limit),
        ("--max-tokens", options.max_tokens),
        ("--sample", options.sample),
        ("--epochs", options.epochs),
    ):
        if count is not None and count < 1:
            raise BadInput(f"{option}: must be at least 1, got {count}")
    for option, value in (
        ("--timeout", options.timeout),
        ("--rpm", options.rpm),
        ("--tpm", options.tpm),
        ("--max-cost", options.max_cost),
    ):
        _number(option, value)
    _number("--temperature", options.temperature, zero=True)
    check_input_mode(options.input_mode)
    if options.scenes is not None and not options.scenes:
        raise BadInput("--scenes: empty list")
    retry = options.retry
    for option, value in (("--retries", retry.max_retries), ("--reasks", retry.max_reasks)):
        if value < 0:
            raise BadInput(f"{option}: must be 0 or more, got {value}")
    _number("retry.base_delay", retry.base_delay, zero=True)
    _number("retry.max_delay", retry.max_delay, zero=True)
    _number("retry.timeout_growth", retry.timeout_growth)


EventKind = Literal["planned", "skipped", "retry", "done", "warning"]


@dataclass(frozen=True)
class ProgressEvent:
    """Something happened to one (scene, task) of one adapter.

    ``planned`` carries ``count`` calls to make; ``skipped`` ``count`` calls already complete
    from an earlier run; ``retry`` one failed attempt about to be repeated; ``done`` a final
    ``status`` with the tokens and cost of all its attempts; ``warning`` something the user
    should know about the whole run, in ``reason`` (sent once per adapter, e.g. a requested
    parameter the provider route dropped).
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
        stopped: Why the run stopped early (``max-cost``, ``setup``, ``interrupted``), or
            ``None``.
        error: What to fix, one line, when ``stopped`` is ``setup`` (an error no retry can
            fix, or a provider that cannot be reached).
        budget: Spent (all sessions), reserved and left, the caps and the pairs the cap kept
            from being sent (:meth:`bpb_core.runner.budget.Spending.summary`).
    """

    run_dir: Path
    adapter: str
    statuses: dict[str, Counter[str]] = field(default_factory=dict)
    cost: float | None = 0.0
    tokens: int = 0
    stopped: str | None = None
    error: str | None = None
    budget: dict[str, Any] = field(default_factory=dict)

    @property
    def api_errors(self) -> int:
        """Pairs that ended with an infrastructure error (resumable)."""
        return sum(c["api_error"] for c in self.statuses.values())

    @property
    def not_sent(self) -> int:
        """Pairs never sent (stopped by the cost cap or a setup failure)."""
        return sum(c["not_sent"] for c in self.statuses.values())
