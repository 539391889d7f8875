"""What the calls of one run share: the adapter, limits, the IO thread and running totals, and
what earlier sessions of its run folder left in the attempts log (read in one pass).

Requests are paced by optional requests-per-minute and tokens-per-minute caps shared by all
calls of a run. Every wait takes the run's ``stop`` event and returns early once it is set
(Ctrl-C, SIGTERM, ``--max-cost``, a setup failure): a call queued for a slot minutes ahead must
not hold the run open after it has stopped sending.

Until the adapter has replied once, its calls go one at a time: an error that every call would
meet (an unknown model, a refused key) then costs one call, not ``--concurrency`` of them. A
provider that cannot be reached stops the adapter after the retry policy's transport budget
(so many connection failures in a row, or so many seconds of them with no reply between).

The attempts log is the run's source of truth: every reply is appended (and flushed) before its
answer file is written. Reading it back gives three things a resumed run needs:

- the configuration hashes of earlier sessions, so a folder whose ``run.json`` is gone still
  cannot mix answers of another adapter, dataset, input mode or prompt setting;
- an ``ok`` reply whose answer file never got written (a kill between the two), which is
  recovered from the log instead of being paid for again;
- the attempts, tokens, cost and latency of every earlier session of a pair, so a pair retried
  in a later session counts all of them (usage tables and retries span sessions).
"""

from __future__ import annotations

import asyncio
import contextlib
import random
import time
from collections.abc import AsyncIterator, Awaitable, Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from bpb_core.errors import ConnectionFailure, SetupFailure
from bpb_core.interfaces import ModelAdapter, Task
from bpb_core.model_calls import ModelRequest, ModelResponse, known_cost
from bpb_core.plugin_calls import call_ceiling
from bpb_core.run_folder import (
    REPLIED,
    AnswerRecord,
    AttemptLog,
    UsageRecord,
    read_attempts,
    write_answer,
)
from bpb_core.runner.budget import Hold, Spending, reservation_entry, settlement_entry
from bpb_core.runner.options import Progress, ProgressEvent, RunOptions

if TYPE_CHECKING:
    from bpb_core.runner.scenes import SceneRef

T = TypeVar("T")


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
            await wait_unless(stop, asyncio.sleep(delay))


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


class NotSent(Exception):
    """The run stopped sending (cost cap or setup failure) while this call waited for a slot."""


@dataclass
class RunState:
    """Shared by every (scene, task) of one run of one adapter."""

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
    budget: TokenBudget = field(default_factory=lambda: TokenBudget(None))
    io: ThreadPoolExecutor = field(
        default_factory=lambda: ThreadPoolExecutor(1, thread_name_prefix="bpb-io")
    )
    spent: float = 0.0
    unpriced: bool = False
    tokens: int = 0
    stop_reason: str | None = None
    setup_error: SetupFailure | None = None
    replied: bool = False
    """Whether the adapter has returned a reply in this session (calls go one at a time till
    then)."""
    first_call: asyncio.Lock = field(default_factory=asyncio.Lock)
    failing: tuple[int, float] | None = None
    """Connection failures in a row and when the first of them came (``None`` after a reply)."""
    model_id: str = ""
    statuses: dict[str, dict[str, int]] = field(default_factory=dict)
    family: str = ""
    simulator: str | None = None
    dropped: set[str] = field(default_factory=set)
    unanswered_seen: set[str] = field(default_factory=set)
    config_hash: str = ""
    history: History = field(default_factory=lambda: History())
    interrupts: int = 0
    stopping: asyncio.Event = field(default_factory=asyncio.Event)
    origins: dict[str, str] = field(default_factory=dict)
    """Who supplied each task (by name) and the adapter (under ``spec``), as
    ``Registered.origin``: a plugin's bug stops the run with one line naming it."""
    spending: Spending = field(default_factory=Spending)
    ledger: AttemptLog | None = None
    """The run folder's spending ledger (:mod:`bpb_core.runner.budget`)."""

    def origin(self, name: str) -> str:
        """Who supplied the task or adapter ``name`` (the name itself when not known)."""
        return self.origins.get(name, repr(name))

    async def offload(self, fn: Callable[..., T], *args: Any) -> T:
        """Run blocking file work on the run's single IO thread (FIFO, so the attempt lines and
        answer files of a pair land in order) while the event loop keeps serving calls."""
        return await asyncio.get_running_loop().run_in_executor(self.io, fn, *args)

    def cot(self, task: str) -> bool:
        """Whether ``task`` asks for chain of thought in this run."""
        return self.options.cot.get(task, self.tasks[task].default_cot)

    def may_send(self) -> bool:
        """False once the run must stop sending (cost cap reached, setup failed, interrupted)."""
        if self.spending.exhausted and self.stop_reason is None:
            self.stop("max-cost")
        return self.stop_reason is None

    def stop(self, reason: str, *, overrides: bool = False) -> None:
        """Send no new call: record ``reason`` (the first one, unless ``overrides``) and wake
        every call waiting for a rate-limit slot or a backoff, so the run ends as soon as the
        calls in flight do."""
        if self.stop_reason is None or overrides:
            self.stop_reason = reason
        self.stopping.set()

    def stop_for_setup(self, error: SetupFailure) -> None:
        """Stop the adapter for good on an error every call would meet (the first is kept)."""
        self.setup_error = self.setup_error or error
        self.stop("setup", overrides=True)

    def connection_failed(self, error: ConnectionFailure) -> None:
        """Count a connection that failed; past the transport budget the adapter stops as for a
        setup failure, naming the endpoint's trouble."""
        now = time.monotonic()
        count, since = self.failing or (0, now)
        self.failing = count + 1, since
        policy = self.options.retry
        if count + 1 >= policy.max_transport_failures or now - since >= policy.transport_window:
            cause = (
                f"provider unreachable: {count + 1} connection failures in a row over "
                f"{now - since:.0f} s with no reply; check --api-base and the network"
            )
            self.stop_for_setup(SetupFailure(cause, str(error)))

    @contextlib.asynccontextmanager
    async def _alone_until_replied(self) -> AsyncIterator[None]:
        """Hold the first-call lock while the adapter has not replied yet (a call queued on
        it goes on at once, without it, when the call before it got a reply)."""
        if not self.replied:
            async with self.first_call:
                if not self.replied:
                    yield
                    return
        yield

    @contextlib.asynccontextmanager
    async def slot(self) -> AsyncIterator[None]:
        """Hold one of the ``--concurrency`` slots, within the rate limit.

        The caller keeps the slot until the reply is logged and its answer file written, so a run
        killed at any instant has at most ``--concurrency`` paid replies that no file records.

        Raises:
            NotSent: The run stopped sending while this call waited for a slot.
        """
        async with self.slots, self._alone_until_replied():
            await self.limiter.wait(self.stopping)  # both return early once the run stops
            await self.budget.wait(self.stopping)
            if not self.may_send():  # checked again here: the cap may be hit while we queued
                raise NotSent
            yield

    async def reserve(self, request: ModelRequest, pair: str) -> Hold | None:
        """Hold the worst case of ``request`` against the run's caps before it is sent,
        waiting while calls in flight may free room (``None``: no cap, or a call the adapter
        cannot price, sent uncounted as ``--allow-unpriced`` lets it be).

        Raises:
            NotSent: It does not fit with no other call in flight (the run stops: ``max-cost``),
                or the run stopped while it waited.
            BadInput: The adapter knows no output limit for the call.
        """
        spending = self.spending
        if not spending.capped:
            return None
        messages, limit = request.messages, request.max_tokens
        ceiling = call_ceiling(self.adapter, self.origin(self.spec), messages, limit)
        if ceiling is None:
            return None
        amount = spending.amount(ceiling, self.spec)
        while (hold := spending.hold(amount, ceiling.input_tokens)) is None:
            if not spending.in_flight:
                self.stop("max-cost")
                raise NotSent
            await wait_unless(self.stopping, spending.room().wait())
            if not self.may_send():
                raise NotSent
        if self.ledger is not None:  # on disk before the call goes: a kill cannot lose it
            await self.offload(self.ledger.append, reservation_entry(hold, pair))
        return hold

    async def settle(
        self, hold: Hold | None, cost: float | None, pair: str, input_tokens: int | None = None
    ) -> None:
        """Count a finished call: its ``cost`` (``None``: unknown, counted at the reservation)
        and free its reservation; the ledger records it."""
        basis = "reply" if cost is not None else "reservation" if hold else "unpriced"
        usd = cost if cost is not None else hold.amount if hold else 0.0
        self.spending.settle(hold, usd, input_tokens)
        if self.ledger is not None:
            await self.offload(self.ledger.append, settlement_entry(hold, usd, pair, basis))
        self.may_send()  # a cap spent: wake the calls queued for a slot now

    def account(self, response: ModelResponse) -> None:
        """Add a reply's tokens and cost to this session's totals."""
        used = (response.usage.input_tokens or 0) + (response.usage.output_tokens or 0)
        self.replied, self.failing = True, None
        self.tokens += used
        self.budget.spent(used)
        if response.cost is None:
            self.unpriced = True
        else:
            self.spent += response.cost
        if response.model_id:
            self.model_id = response.model_id

    def note_dropped(self, task: str, names: tuple[str, ...]) -> None:
        """Warn once per run about each requested parameter the provider route dropped."""
        new = sorted(set(names) - self.dropped)
        if not new:
            return
        self.dropped.update(new)
        said = f"requested {', '.join(new)} not sent to the model (dropped by the provider route)"
        self.warn(task, f"{said}; run.json and the report mark this run")

    def note_unanswered(self, task: str, kind: str, error: str) -> None:
        """Warn once per run about replies of each ``kind`` (refused, cut, empty): a cut
        names the cap, a setting of the run the user may want to raise."""
        if kind in self.unanswered_seen:
            return
        self.unanswered_seen.add(kind)
        self.warn(task, f"{error} (scored wrong, not re-asked; the report counts them per task)")

    def warn(self, task: str, reason: str) -> None:
        """Tell the user something about the whole run (printed above the progress bars)."""
        self.progress.update(ProgressEvent(self.spec, task, "warning", reason=reason))

    def not_sent(self, task: str, pair: str = "") -> None:
        """Record a pair left unsent (cost cap or setup stop); it stays resumable. ``pair``:
        ``scene/task``, kept in the run's summary when the cost cap stopped it."""
        if pair and self.stop_reason == "max-cost":
            self.spending.kept.append(pair)
        self.count(task, "not_sent")
        self.progress.update(ProgressEvent(self.spec, task, "done", status="not_sent"))

    def count(self, task: str, status: str) -> None:
        """Count one pair of ``task`` that ended with ``status``."""
        by_status = self.statuses.setdefault(task, {})
        by_status[status] = by_status.get(status, 0) + 1


@dataclass
class Tally:
    """Usage, cost and latency summed over the attempts of one (scene, task)."""

    attempts: int = 0
    responses: int = 0
    usage: UsageRecord = field(default_factory=UsageRecord)
    cost: float | None = 0.0
    latency: float = 0.0

    def add(self, response: ModelResponse) -> None:
        """Add one reply (cost becomes unknown once any reply has no price)."""
        u = response.usage
        self.responses += 1
        self.usage.input_tokens += u.input_tokens or 0
        self.usage.output_tokens += u.output_tokens or 0
        self.usage.reasoning_tokens += u.reasoning_tokens or 0
        self.usage.cached_tokens += u.cached_tokens or 0
        if self.cost is not None:
            self.cost = None if response.cost is None else self.cost + response.cost
        self.latency += response.latency

    def record(self, ref: SceneRef, task: str, adapter: str, **fields: Any) -> AnswerRecord:
        """The answer record of ``task`` about ``ref`` with these totals (``fields``: the rest)."""
        return AnswerRecord(
            scene_id=ref.scene_id,
            horizon=ref.key.horizon,
            index=ref.key.index,
            task=task,
            adapter=adapter,
            attempts=self.attempts,
            usage=self.usage.model_copy(),
            cost=self.cost if self.responses else None,
            latency=self.latency,
            **fields,
        )


_USAGE = ("input_tokens", "output_tokens", "reasoning_tokens", "cached_tokens")


@dataclass
class PairHistory:
    """The logged attempts of one (scene, task): their totals, and its last ``ok`` reply."""

    tally: Tally = field(default_factory=Tally)
    ok: dict[str, Any] | None = None

    def add(self, entry: dict[str, Any]) -> None:
        """Count one logged attempt."""
        tally = self.tally
        tally.attempts += 1
        if entry.get("outcome") not in REPLIED:
            return
        tally.responses += 1
        usage = entry.get("usage") or {}
        for name in _USAGE:
            value = usage.get(name) if isinstance(usage, dict) else None
            if isinstance(value, int):
                setattr(tally.usage, name, getattr(tally.usage, name) + value)
        cost = known_cost(entry.get("cost"))  # a NaN logged by an older bpb: unknown
        if tally.cost is not None:
            tally.cost = None if cost is None else tally.cost + cost
        latency = entry.get("latency")
        tally.latency += float(latency) if isinstance(latency, (int, float)) else 0.0
        if entry.get("outcome") == "ok" and isinstance(entry.get("answer"), dict):
            self.ok = entry


@dataclass
class History:
    """Configuration hashes seen and per-pair histories of one run folder."""

    configs: set[str] = field(default_factory=set)
    pairs: dict[tuple[str, str, int], PairHistory] = field(default_factory=dict)

    def prior(self, scene_id: str, task: str, epoch: int = 1) -> Tally:
        """A copy of the sample's totals so far (zero when it was never sent)."""
        found = self.pairs.get((scene_id, task, epoch))
        if found is None:
            return Tally()
        old = found.tally
        return Tally(old.attempts, old.responses, old.usage.model_copy(), old.cost, old.latency)


def read_history(run_dir: Path, adapter: str, keep: Iterable[tuple[str, str, int]] = ()) -> History:
    """Read the attempts log of ``run_dir`` once.

    Args:
        run_dir: The run folder.
        adapter: The run's name; attempts logged under another name are ignored for totals
            (their configuration hash still counts).
        keep: ``(scene_id, task, epoch)`` samples to collect totals for (others are only
            hashed).
    """
    wanted = set(keep)
    history = History()
    for entry in read_attempts(run_dir):
        config = entry.get("config")
        if isinstance(config, str):
            history.configs.add(config)
        epoch = entry.get("epoch", 1)
        pair = (str(entry.get("scene_id")), str(entry.get("task")), epoch)
        if pair in wanted and entry.get("adapter") == adapter:
            history.pairs.setdefault(pair, PairHistory()).add(entry)
    return history


def recover_answers(
    run_dir: Path,
    history: History,
    pending: Iterable[tuple[SceneRef, str, int]],
    state: RunState,
) -> set[tuple[str, str, int]]:
    """Write the answer file of every pending pair whose ``ok`` reply is already in the log.

    Args:
        run_dir: The run folder.
        history: Its attempts log, read by :func:`read_history`.
        pending: The pairs without a finished answer file.
        state: The run (its name, input mode and chain of thought per task, which the
            configuration hash guarantees the logged session shared).

    Returns:
        The ``(scene_id, task, epoch)`` samples recovered (never sent again).
    """
    recovered = set()
    for ref, task, epoch in pending:
        found = history.pairs.get((ref.scene_id, task, epoch))
        if found is None or found.ok is None:
            continue
        record = found.tally.record(
            ref,
            task,
            state.spec,
            status="ok",
            answer=found.ok["answer"],
            rule=found.ok.get("rule"),
            finish_reason=found.ok.get("finish_reason"),
            input_mode=state.options.input_mode,
            cot=state.cot(task),
            epoch=epoch,
        )
        write_answer(run_dir, ref.key, record)
        recovered.add((ref.scene_id, task, epoch))
    return recovered
