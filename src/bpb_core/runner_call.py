"""One (scene, task) of a run: the call, bpb's retries, and what is written about it.

Infrastructure errors (429, 5xx, timeouts, dropped connections) are retried with exponential
backoff and full jitter, honouring a server's Retry-After; a timeout also lengthens the next
timeout. A malformed answer is re-asked in a fresh conversation with an escalated prompt and a
longer timeout. Other 4xx fail at once. An authentication failure stops the whole run.
"""

from __future__ import annotations

import asyncio
import random
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, TypeVar

from bpb_core.adapters import ModelRequest, ModelResponse
from bpb_core.errors import AuthenticationFailed, ModelError, ModelTimeout, ParseFailure
from bpb_core.interfaces import ModelAdapter, PromptOptions, Task
from bpb_core.runner_data import SceneRef
from bpb_core.runner_limits import RateLimiter
from bpb_core.runner_types import Progress, ProgressEvent, RunOptions
from bpb_core.scene import Scene
from bpb_core.storage import AnswerRecord, AttemptLog, UsageRecord, write_answer

T = TypeVar("T")


@dataclass
class RunState:
    """What the calls of one run share: adapter, limits, logs and the running totals."""

    adapter: ModelAdapter
    spec: str
    tasks: dict[str, Task]
    options: RunOptions
    run_dir: Path
    log: AttemptLog
    progress: Progress
    limiter: RateLimiter
    slots: asyncio.Semaphore
    rng: random.Random
    io: ThreadPoolExecutor = field(
        default_factory=lambda: ThreadPoolExecutor(1, thread_name_prefix="bpb-io")
    )
    spent: float = 0.0
    unpriced: bool = False
    tokens: int = 0
    stop_reason: str | None = None
    auth_error: AuthenticationFailed | None = None
    model_id: str = ""
    statuses: dict[str, dict[str, int]] = field(default_factory=dict)

    async def offload(self, fn: Callable[..., T], *args: Any) -> T:
        """Run blocking file work on the run's single IO thread (FIFO, so the attempt lines and
        answer files of a pair land in order) while the event loop keeps serving calls."""
        return await asyncio.get_running_loop().run_in_executor(self.io, fn, *args)

    def cot(self, task: str) -> bool:
        return self.options.cot.get(task, self.tasks[task].default_cot)

    def may_send(self) -> bool:
        """False once the run must stop sending (cost cap reached or auth failed)."""
        cap = self.options.max_cost
        if cap is not None and self.spent >= cap and self.stop_reason is None:
            self.stop_reason = "max-cost"
        return self.stop_reason is None

    def not_sent(self, task: str) -> None:
        """Record a pair left unsent (cost cap or auth stop); it stays resumable."""
        self.count(task, "not_sent")
        self.progress.update(ProgressEvent(self.spec, task, "done", status="not_sent"))

    def count(self, task: str, status: str) -> None:
        by_status = self.statuses.setdefault(task, {})
        by_status[status] = by_status.get(status, 0) + 1


@dataclass
class _Tally:
    attempts: int = 0
    responses: int = 0
    usage: UsageRecord = field(default_factory=UsageRecord)
    cost: float | None = 0.0
    latency: float = 0.0

    def add(self, response: ModelResponse) -> None:
        u = response.usage
        self.responses += 1
        self.usage.input_tokens += u.input_tokens or 0
        self.usage.output_tokens += u.output_tokens or 0
        self.usage.reasoning_tokens += u.reasoning_tokens or 0
        self.usage.cached_tokens += u.cached_tokens or 0
        self.cost = (
            None if self.cost is None or response.cost is None else self.cost + response.cost
        )
        self.latency += response.latency


def _backoff(state: RunState, retry: int, error: ModelError) -> float:
    policy = state.options.retry
    hinted = getattr(error, "retry_after", None)
    if hinted is not None:
        return float(min(hinted, policy.max_delay))
    ceiling = min(policy.max_delay, policy.base_delay * 2 ** (retry - 1))
    return state.rng.uniform(ceiling / 2, ceiling)


class _NotSent(Exception):
    """The run stopped sending (cost cap or auth failure) while this call waited for a slot."""


async def _send(state: RunState, request: ModelRequest) -> ModelResponse:
    async with state.slots:
        await state.limiter.wait()
        if not state.may_send():  # checked again here: the cap may be hit while we queued
            raise _NotSent
        return await state.adapter.complete(request)


def _account(state: RunState, response: ModelResponse, tally: _Tally) -> None:
    tally.add(response)
    state.tokens += (response.usage.input_tokens or 0) + (response.usage.output_tokens or 0)
    if response.cost is None:
        state.unpriced = True
    else:
        state.spent += response.cost
    if response.model_id:
        state.model_id = response.model_id


async def _log(state: RunState, ref: SceneRef, task: str, **fields: Any) -> None:
    entry = {"time": time.time(), "scene_id": ref.scene_id, "task": task, "adapter": state.spec}
    entry.update(fields)
    await state.offload(state.log.append, entry)


@dataclass
class _Attempt:
    """The evolving shape of the next attempt."""

    escalation: int = 0
    timeout: float = 0.0
    retries: int = 0
    reasks: int = 0
    last_error: str | None = None
    finish_reason: str | None = None


async def answer(
    state: RunState,
    ref: SceneRef,
    scene: Scene,
    image: bytes | None,
    image_sha: str | None,
    task_name: str,
) -> None:
    """Ask one task about one scene until it is answered, malformed for good, or failed."""
    task, cot = state.tasks[task_name], state.cot(task_name)
    base = PromptOptions(state.options.input_mode, cot, state.options.force_numeric)
    tally, attempt = _Tally(), _Attempt(timeout=state.options.timeout)
    while True:
        if not state.may_send():
            state.not_sent(task_name)
            return
        prompt = replace(base, escalation=attempt.escalation)
        request = ModelRequest(
            task.messages(scene, image, prompt),
            task_name,
            scene,
            state.options.temperature,
            state.options.max_tokens,
            attempt.timeout,
            tally.attempts + 1,
        )
        tally.attempts += 1
        started = time.perf_counter()
        common = {
            "attempt": tally.attempts,
            "escalation": attempt.escalation,
            "timeout": attempt.timeout,
            "image_sha256": image_sha,
        }
        try:
            response = await _send(state, request)
        except _NotSent:
            state.not_sent(task_name)
            return
        except ModelError as error:
            elapsed = time.perf_counter() - started
            if not await _on_model_error(state, ref, task_name, error, attempt, common, elapsed):
                await _finish(state, ref, task_name, cot, "api_error", None, tally, attempt)
                return
            continue
        _account(state, response, tally)
        attempt.finish_reason = response.finish_reason
        outcome = _parse(task, response, scene, prompt)
        await _log(
            state,
            ref,
            task_name,
            **common,
            outcome=outcome[0],
            text=response.text,
            finish_reason=response.finish_reason,
            usage=vars(response.usage),
            cost=response.cost,
            latency=response.latency,
            model_id=response.model_id,
            rule=outcome[1],
            error=outcome[2],
        )
        if outcome[0] == "ok":
            await _finish(state, ref, task_name, cot, "ok", outcome[3], tally, attempt, outcome[1])
            return
        attempt.last_error = outcome[2]
        if attempt.reasks >= state.options.retry.max_reasks:
            await _finish(state, ref, task_name, cot, "parse_error", None, tally, attempt)
            return
        attempt.reasks += 1
        attempt.escalation += 1
        attempt.timeout *= state.options.retry.timeout_growth
        state.progress.update(ProgressEvent(state.spec, task_name, "retry", reason="format"))


def _parse(
    task: Task, response: ModelResponse, scene: Scene, prompt: PromptOptions
) -> tuple[str, str | None, str | None, dict[str, Any] | None]:
    try:
        parsed = task.parse(response.text, scene, prompt)
    except ParseFailure as failure:
        reason = str(failure)
        if response.finish_reason == "length":
            reason = f"reply cut off by the token limit (finish_reason length); {reason}"
        return "parse_error", None, reason, None
    return "ok", parsed.rule, None, parsed.value


async def _on_model_error(
    state: RunState,
    ref: SceneRef,
    task: str,
    error: ModelError,
    attempt: _Attempt,
    common: dict[str, Any],
    elapsed: float,
) -> bool:
    """Log a failed call; sleep and return True when it is worth another try."""
    message = f"{type(error).__name__}: {error}"
    attempt.last_error = message
    retry = error.retryable and attempt.retries < state.options.retry.max_retries
    delay = _backoff(state, attempt.retries + 1, error) if retry else None
    await _log(
        state,
        ref,
        task,
        **common,
        outcome="api_error",
        error=message,
        latency=elapsed,
        retry_in=delay,
    )
    if isinstance(error, AuthenticationFailed):
        state.auth_error = state.auth_error or error
        state.stop_reason = "auth"
        return False
    if not retry or delay is None:
        return False
    attempt.retries += 1
    if isinstance(error, ModelTimeout):
        attempt.timeout *= state.options.retry.timeout_growth
    state.progress.update(ProgressEvent(state.spec, task, "retry", reason=type(error).__name__))
    await asyncio.sleep(delay)
    return True


async def _finish(
    state: RunState,
    ref: SceneRef,
    task: str,
    cot: bool,
    status: str,
    value: dict[str, Any] | None,
    tally: _Tally,
    attempt: _Attempt,
    rule: str | None = None,
) -> None:
    record = AnswerRecord(
        scene_id=ref.scene_id,
        horizon=ref.key.horizon,
        index=ref.key.index,
        task=task,
        adapter=state.spec,
        status=status,
        answer=value,
        rule=rule,
        finish_reason=attempt.finish_reason,
        attempts=tally.attempts,
        usage=tally.usage,
        cost=tally.cost if tally.responses else None,
        latency=tally.latency,
        error=None if status == "ok" else attempt.last_error,
        input_mode=state.options.input_mode,
        cot=cot,
    )
    await state.offload(write_answer, state.run_dir, ref.key, record)
    state.count(task, status)
    tokens = record.usage.input_tokens + record.usage.output_tokens
    state.progress.update(
        ProgressEvent(state.spec, task, "done", status=status, tokens=tokens, cost=record.cost)
    )
