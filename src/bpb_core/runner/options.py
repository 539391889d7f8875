"""Options of an evaluation run: what is asked, how, and how hard bpb tries."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

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
        max_cost: Stop sending calls once the run has spent this many USD.
        seed: Seed for adapters with randomness.
        retry: Retry policy.
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
    structured_output: bool = False
