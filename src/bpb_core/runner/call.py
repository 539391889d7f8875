"""One (scene, task) of a run: the call, bpb's retries, and what is written about it.

Infrastructure errors (429, 5xx, timeouts, dropped connections) are retried with exponential
backoff and full jitter, honouring a server's Retry-After; a timeout also lengthens the next
timeout. A malformed answer is re-asked in a fresh conversation with an escalated prompt and a
longer timeout. A 4xx about one request fails that pair at once. An error no retry can fix (a
:class:`SetupFailure`: unknown model, invalid parameter, spent quota, refused key) stops the
adapter at its first occurrence; so do repeated connection failures.

A reply the model declined (a refusal, or one a safety filter stopped), one cut at the token
cap and one with no text hold no answer, and asking again the same way would pay for the same
reply: they are recorded as such (the pair's status is ``refused``, ``cut`` or ``empty``), never
re-asked as if malformed, and scored wrong like a parse error. A cut says which cap cut it: a
cap set too low is a setting of the run, not something the model got wrong.
"""

from __future__ import annotations

import asyncio
import dataclasses
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

from bpb_core.capabilities import PublishesSchema
from bpb_core.errors import (
    ConnectionFailure,
    ModelError,
    ModelTimeout,
    ParseFailure,
    PluginBug,
    SetupFailure,
    blamed,
)
from bpb_core.interfaces import PromptOptions
from bpb_core.model_calls import ModelRequest, ModelResponse, Usage, known_cost, valid_unicode
from bpb_core.plugin_calls import parsed_answer, prompt_messages, published_schema
from bpb_core.run_folder import NoAnswer, write_answer
from bpb_core.runner.budget import Hold, pair_name
from bpb_core.runner.options import ProgressEvent
from bpb_core.runner.scenes import SceneRef
from bpb_core.runner.state import NotSent, RunState, Tally, wait_unless


def unanswered(response: ModelResponse) -> NoAnswer | None:
    """``refused``, ``cut`` or ``empty`` for a reply that holds no answer; ``None`` for one
    to parse. A refusal wins over a cut, a cut over an empty text (a reply whose whole cap
    went on reasoning is cut, not empty)."""
    if response.refusal or response.finish_reason == "content_filter":
        return "refused"
    if response.finish_reason == "length":
        return "cut"
    if not response.text.strip():
        return "empty"
    return None


def _caps(sent: Mapping[str, Any]) -> Iterator[str]:
    for key, value in sent.items():
        if isinstance(value, Mapping):
            yield from _caps(value)
        elif "max" in key.lower() and "token" in key.lower():
            yield f"{key}={value}"


def unanswered_error(kind: NoAnswer, response: ModelResponse, asked: int | None) -> str:
    """The one line a refused, cut or empty reply records as its error."""
    finish = response.provider_finish or response.finish_reason
    if kind == "refused":
        said = f": {response.refusal}" if response.refusal else ""
        return f"refused by the model or its safety filter (finish {finish}){said}"
    if kind == "cut":  # the cap as sent (max_tokens=4000), else as the run asked it
        cap = next(_caps(response.sent or {}), None) or (
            f"max_tokens={asked}" if asked is not None else "the provider's default max tokens"
        )
        setting = "a setting of the run, raise --max-tokens"
        return f"cut at the token cap ({cap}, finish {finish}): {setting}"
    return f"empty reply (finish {finish})"


def _parse(
    call: PairCall, response: ModelResponse, prompt: PromptOptions
) -> tuple[dict[str, Any] | None, str | None, str | None]:
    """The answer and the rule that read it, or the reason it could not be read."""
    try:
        task = call.state.tasks[call.task]
        parsed = parsed_answer(
            task, call.state.origin(call.task), response.text, call.scene, prompt
        )
    except ParseFailure as failure:
        return None, None, str(failure)
    return parsed.value, parsed.rule, None


@dataclass
class PairCall:
    """Asks one task about one scene until it is answered, malformed for good, or failed."""

    state: RunState
    ref: SceneRef
    scene: Any
    image: bytes | None
    image_sha: str | None
    task: str
    epoch: int = 1
    tally: Tally = field(default_factory=Tally)
    escalation: int = 0
    retries: int = 0
    reasks: int = 0
    timeout: float = 0.0
    last_error: str | None = None
    finish_reason: str | None = None
    metadata: dict[str, bool | float | str] = field(default_factory=dict)

    async def run(self) -> None:
        """Attempt until the pair is settled (its answer file written) or the run stops."""
        self.timeout = self.state.options.timeout
        while not await self._attempt():
            pass

    async def _attempt(self) -> bool:
        """One attempt; True when the pair is settled."""
        if not self.state.may_send():
            self.state.not_sent(self.task, self.pair)
            return True
        prompt = PromptOptions(
            self.state.options.input_mode,
            self.state.cot(self.task),
            self.state.options.force_numeric,
            self.escalation,
        )
        self.tally.attempts += 1
        delay: float | None = None
        try:
            async with self.state.slot():  # held until the reply is logged and written
                request = self._request(prompt)  # a task's bug stops the run: PluginBug
                hold = await self.state.reserve(request, self.pair)
                started = time.perf_counter()
                spec = self.state.spec
                try:
                    # Any other exception is the adapter's bug: the run stops naming it, like a
                    # task's; a call meant to fail alone raises a model error (RequestRejected).
                    with blamed(self.state.origin(spec), f"adapter {spec!r}: complete()"):
                        response = await self.state.adapter.complete(request)
                except ModelError as error:
                    if hold is not None:  # a timed-out call may have been billed: in full
                        cost = None if isinstance(error, ModelTimeout) else 0.0
                        await self.state.settle(hold, cost, self.pair)
                    delay = await self._failed(error, time.perf_counter() - started)
                else:
                    return await self._replied(self._checked(response), prompt, hold)
        except NotSent:
            self.state.not_sent(self.task, self.pair)
            return True
        if delay is None:
            return True
        await wait_unless(self.state.stopping, asyncio.sleep(delay))  # outside the slot
        return False

    @property
    def pair(self) -> str:
        """The pair's name in the spending ledger and the run's summary."""
        return pair_name(self.ref.scene_id, self.task, self.epoch)

    def _request(self, prompt: PromptOptions) -> ModelRequest:
        task, origin = self.state.tasks[self.task], self.state.origin(self.task)
        messages = prompt_messages(task, origin, self.scene, self.image, prompt)
        options = self.state.options
        return ModelRequest(
            messages,
            self.task,
            self.scene,
            self.state.family,
            self.state.simulator,
            options.temperature,
            options.max_tokens,
            self.timeout,
            self.tally.attempts,
            self._schema(),
        )

    def _checked(self, response: object) -> ModelResponse:
        """The adapter's reply, if it is a :class:`ModelResponse` with text and usage; lone
        surrogates in its strings (a reply's JSON may carry ``"\\udc80"``) become U+FFFD, so
        the attempts log, the answer file and the pages can hold them."""
        if isinstance(response, ModelResponse):
            if isinstance(response.text, str) and isinstance(response.usage, Usage):
                return dataclasses.replace(
                    response,
                    text=valid_unicode(response.text),
                    reasoning=_valid(response.reasoning),
                    model_id=_valid(response.model_id),
                    metadata=_valid(response.metadata),
                )
            what = f"a ModelResponse with text {type(response.text).__name__} and usage "
            what += type(response.usage).__name__
        else:
            what = type(response).__name__
        spec = self.state.spec
        raise PluginBug(
            f"{self.state.origin(spec)}: adapter {spec!r}: complete() returned {what}; "
            "expected a bpb_core.ModelResponse (text a str, usage a bpb_core.Usage)"
        )

    def _schema(self) -> dict[str, Any] | None:
        task = self.state.tasks[self.task]
        if self.state.options.structured_output and isinstance(task, PublishesSchema):
            return published_schema(task, self.state.origin(self.task))
        return None

    async def _log(self, **fields: Any) -> None:
        entry = {
            "time": time.time(),
            "scene_id": self.ref.scene_id,
            "task": self.task,
            "epoch": self.epoch,
            "adapter": self.state.spec,
            "attempt": self.tally.attempts,
            "escalation": self.escalation,
            "timeout": self.timeout,
            "image_sha256": self.image_sha,
            "config": self.state.config_hash,
            **fields,
        }
        await self.state.offload(self.state.log.append, entry)

    async def _replied(
        self, response: ModelResponse, prompt: PromptOptions, hold: Hold | None
    ) -> bool:
        if response.cost is not None and known_cost(response.cost) is None:
            response = dataclasses.replace(response, cost=None)  # an adapter's NaN: unknown
        self.tally.add(response)
        self.state.account(response)
        await self.state.settle(hold, response.cost, self.pair, response.usage.input_tokens)
        self.finish_reason = response.finish_reason
        self.metadata = dict(response.metadata)
        kind = unanswered(response)
        if kind is None:
            # Parsing is linear but a reply may be up to a megabyte: keep the loop serving.
            value, rule, error = await asyncio.to_thread(_parse, self, response, prompt)
        else:
            value, rule = None, None
            error = unanswered_error(kind, response, self.state.options.max_tokens)
        outcome = kind or ("ok" if error is None else "parse_error")
        # the attempt line: its outcome, text, finish and refusal, usage
        said = {"refusal": response.refusal} if response.refusal else {}
        if response.provider_finish not in (None, response.finish_reason):
            said["provider_finish"] = response.provider_finish
        await self._log(
            outcome=outcome,
            text=response.text,
            finish_reason=response.finish_reason,
            **said,
            usage=vars(response.usage),
            cost=response.cost,
            latency=response.latency,
            model_id=response.model_id,
            rule=rule,
            answer=value,
            error=error,
            sent=response.sent,
            dropped=list(response.dropped),
            reasoning=response.reasoning,
            **({"metadata": response.metadata} if response.metadata else {}),
        )
        self.state.note_dropped(self.task, response.dropped)
        if error is None:
            await self._settle("ok", value, rule)
            return True
        self.last_error = error
        if kind is not None:  # asking again the same way would buy the same reply
            self.state.note_unanswered(self.task, kind, error)
            await self._settle(kind)
            return True
        if self.reasks >= self.state.options.retry.max_reasks:
            await self._settle("parse_error")
            return True
        self.reasks += 1
        self.escalation += 1
        self.timeout *= self.state.options.retry.timeout_growth
        self._retrying("format")
        return False

    async def _failed(self, error: ModelError, elapsed: float) -> float | None:
        """Log a failed call; settle the pair and return None, or return the seconds to back
        off before another try. An error no retry can fix stops the adapter; so do too many
        connection failures in a row (:meth:`RunState.connection_failed`)."""
        self.last_error = f"{type(error).__name__}: {error}"
        policy = self.state.options.retry
        if isinstance(error, SetupFailure):
            self.state.stop_for_setup(error)
        elif isinstance(error, ConnectionFailure):
            self.state.connection_failed(error)
        retry = error.retryable and self.retries < policy.max_retries
        delay = self._backoff(error) if retry else None
        await self._log(outcome="api_error", error=self.last_error, latency=elapsed, retry_in=delay)
        if delay is None:
            await self._settle("api_error")
            return None
        self.retries += 1
        if isinstance(error, ModelTimeout):
            self.timeout *= policy.timeout_growth
        self._retrying(type(error).__name__)
        return delay

    def _backoff(self, error: ModelError) -> float:
        """Seconds to wait: the server's Retry-After, else exponential with full jitter."""
        policy = self.state.options.retry
        hinted = getattr(error, "retry_after", None)
        if hinted is not None:
            return float(min(hinted, policy.max_delay))
        ceiling = min(policy.max_delay, policy.base_delay * 2**self.retries)
        return self.state.rng.uniform(ceiling / 2, ceiling)

    def _retrying(self, reason: str) -> None:
        self.state.progress.update(
            ProgressEvent(self.state.spec, self.task, "retry", reason=reason)
        )

    async def _settle(
        self, status: str, value: dict[str, Any] | None = None, rule: str | None = None
    ) -> None:
        """Write the pair's answer file (atomically, on the IO thread) and report it."""
        record = self.tally.record(
            self.ref,
            self.task,
            self.state.spec,
            status=status,
            answer=value,
            rule=rule,
            finish_reason=self.finish_reason,
            error=None if status == "ok" else self.last_error,
            input_mode=self.state.options.input_mode,
            cot=self.state.cot(self.task),
            epoch=self.epoch,
            metadata=self.metadata,
        )
        await self.state.offload(write_answer, self.state.run_dir, self.ref.key, record)
        self.state.count(self.task, status)
        tokens = record.usage.input_tokens + record.usage.output_tokens
        self.state.progress.update(
            ProgressEvent(
                self.state.spec, self.task, "done", status=status, tokens=tokens, cost=record.cost
            )
        )


def _valid(value: Any) -> Any:
    """``value`` (a string, or a mapping of them) with lone surrogates replaced."""
    if isinstance(value, dict):
        return {k: _valid(v) for k, v in value.items()}
    return valid_unicode(value) if isinstance(value, str) else value
