"""``litellm:<model>``: one chat completion per request through ``litellm.acompletion``.

bpb owns retries, so every call passes ``max_retries=0`` (the openai SDK inside litellm would
otherwise retry 429/5xx/timeouts on its own) and never ``num_retries``. Prices come from
litellm's bundled price map (``LITELLM_LOCAL_MODEL_COST_MAP=True``, so nothing is fetched); a
model without a price costs ``None``, never 0. Keys come from the provider's usual environment
variables and are never logged.
"""

from __future__ import annotations

import asyncio
import base64
import dataclasses
import functools
import logging
import os
import re
import time
import uuid
from typing import Any

from bpb_adapters.litellm_adapter import prices, rules, wire
from bpb_adapters.litellm_adapter.aliases import (
    map_entry,
    preflight,
    provider_of,
    quick_preflight,
    resolve,
)
from bpb_adapters.litellm_adapter.errors import map_error
from bpb_core.errors import BadInput, ModelError, ModelTimeout, ServerError, need_module
from bpb_core.model_calls import (
    AdapterOptions,
    CallCeiling,
    Message,
    ModelRequest,
    ModelResponse,
    TextPart,
    Usage,
    non_finite,
)

_TIMEOUT_GRACE = 5.0  # our own watchdog beyond the HTTP timeout, in case a layer ignores it
_REASONING_CAP = 8000  # characters of reasoning text kept per reply


def _import_litellm() -> Any:
    # Always the bundled price map: a run must never reach out for prices, whatever the shell
    # says. litellm reads the variable when it is imported, so it is set for the import only:
    # the calling program's environment is left as it was.
    name, before = "LITELLM_LOCAL_MODEL_COST_MAP", os.environ.get("LITELLM_LOCAL_MODEL_COST_MAP")
    os.environ[name] = "True"
    try:
        litellm: Any = need_module("litellm", "the litellm adapter", "pip install 'bpb[litellm]'")
    finally:
        if before is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = before
    litellm.suppress_debug_info = True
    litellm.set_verbose = False
    litellm.telemetry = False
    # A reasoning effort sent through OpenAI's Responses API asks for the reasoning summary
    # too (``reasoning.summary``): it is kept with the answer, as other providers' thinking is.
    litellm.reasoning_auto_summary = True
    logger = logging.getLogger("LiteLLM")
    if logger.level == logging.NOTSET:  # bpb reports through its own channels; a level the
        logger.setLevel(logging.ERROR)  # calling program chose is its own
    wire.install(litellm)
    return litellm


def _data_uri(data: bytes, media_type: str) -> str:
    """The base64 data URI of an image."""
    return f"data:{media_type};base64,{base64.b64encode(data).decode('ascii')}"


class LiteLLMAdapter:
    """Talks to one model through litellm.

    Args:
        model: The name the user gave (an alias or a litellm model string).
        options: ``api_base``, model arguments, price overrides and aliases.

    Raises:
        BadInput: A price override is malformed, a model argument is NaN or infinite, or the
            provider rejects the arguments together (:mod:`~bpb_adapters.litellm_adapter.rules`).
    """

    def __init__(self, model: str, options: AdapterOptions) -> None:
        self.model = resolve(model, options.aliases)
        self.args = dict(options.model_args)
        bad = non_finite(self.args)
        if bad is not None:  # sent as JSON, which has no NaN: every call would fail
            raise BadInput(f"model argument {bad[0]}: must be a finite number, got {bad[1]!r}")
        self._plan = rules.plan(self.model, self.args, map_entry(self.model))
        self._hidden = wire.secrets(self.args)
        tag = self._tag(options.label)
        self.name = f"litellm:{model}" + (f" [{tag}]" if tag else "")
        self._api_base = options.api_base
        # each adapter keeps the URIs of its recent images (a scene's tasks share one image)
        self._uri = functools.lru_cache(maxsize=256)(_data_uri)
        self._override = options.prices.get(model) or options.prices.get(self.model)
        if self._override is not None:
            try:
                prices.litellm_entry(self._override, None)
            except ValueError as exc:
                raise BadInput(f"price of {model}: {exc}") from None
        self._loaded: Any = None
        self._priced = False

    def _tag(self, label: str | None) -> str:
        """The option set's name: the user's label or one made from the arguments, then the
        rules' rewrites (a label never hides that a budget was sent as an effort)."""
        if label is None:
            kept = {k: v for k, v in self.args.items() if k not in self._plan.replaced}
            return wire.label(kept, self._plan.tags)
        return ",".join([label, *self._plan.tags]) if label else ",".join(self._plan.tags)

    @property
    def _litellm(self) -> Any:
        """litellm, imported on first use (a failing preflight need not pay for it)."""
        if self._loaded is None:
            self._loaded = _import_litellm()
            self._priced = prices.has_price(self._loaded.model_cost, self.model)
            if self._override is not None:
                provider = provider_of(self._loaded, self.model, self._api_base)
                prices.register(self._loaded, self.model, provider, self._override)
                self._priced = True
        return self._loaded

    @property
    def priced(self) -> bool:
        """Whether a cost can be given for this model (bundled map or an override)."""
        return self._litellm is not None and self._priced

    def estimate(self, messages: tuple[Message, ...]) -> tuple[int, float | None]:
        """Input tokens and input cost of ``messages`` by the provider's rules."""
        provider = provider_of(self._litellm, self.model, self._api_base)
        return prices.estimate(self._litellm, self.model, provider, messages, self.priced)

    def ceiling(self, messages: tuple[Message, ...], max_tokens: int | None) -> CallCeiling | None:
        """The most one call with ``messages`` may cost: its input as :meth:`estimate` counts
        it, and output at the call's token cap (``None`` without a price)."""
        tokens, cost = self.estimate(messages)
        price = prices.output_price(self._litellm, self.model) if cost is not None else None
        if cost is None or price is None:
            return None
        limit, source = prices.output_limit(self._litellm, self.model, max_tokens, self.args)
        priced_by = "the run's price" if self._override is not None else "litellm's price map"
        provider = provider_of(self._litellm, self.model, self._api_base) or "openai"
        basis = f"litellm token counter, {provider} image rule; {priced_by}; output cap {source}"
        return CallCeiling(tokens, cost, limit, price, basis)

    def preflight(self) -> str | None:
        """Provider known, key present, route modules importable (one line if not)."""
        quick = quick_preflight(self.model, self._api_base, self.args)
        if quick is not None:
            return quick
        return preflight(self._litellm, self.model, self._api_base, self.args)

    def settings(self) -> dict[str, Any]:
        """The model id, the model arguments (secrets masked), the provider rules' rewrites
        and the api_base, for run.json (a resume may change the api_base: it does not shape
        answers)."""
        found = {"model": self.model, "model_args": wire.recorded(self.args)}
        if self._plan.notes:
            found["rules"] = list(self._plan.notes)
        return {**found, "api_base": self._api_base}

    def _content(self, message: Message) -> str | list[dict[str, Any]]:
        if all(isinstance(p, TextPart) for p in message.parts):
            return "\n\n".join(p.text for p in message.parts if isinstance(p, TextPart))
        parts: list[dict[str, Any]] = []
        for part in message.parts:
            if isinstance(part, TextPart):
                parts.append({"type": "text", "text": part.text})
            else:
                url = self._uri(part.data, part.media_type)
                parts.append({"type": "image_url", "image_url": {"url": url}})
        return parts

    async def complete(self, request: ModelRequest) -> ModelResponse:
        """Send ``request``; raise a :mod:`bpb_core.errors` model error on failure."""
        started = time.perf_counter()
        requested: dict[str, Any] = {}
        if self._plan.temperature:
            requested["temperature"] = request.temperature
        if request.max_tokens is not None:
            requested["max_tokens"] = request.max_tokens
        if request.response_schema is not None:
            requested["response_format"] = response_format(request)
        requested.update(self._plan.args)  # a model's own arguments win over the run's
        kwargs: dict[str, Any] = {
            "model": self.model,
            "messages": [{"role": m.role, "content": self._content(m)} for m in request.messages],
            **requested,
            "timeout": request.timeout,
            "max_retries": 0,
            "drop_params": True,
        }
        if self._api_base:
            kwargs["api_base"] = self._api_base
        call_id = kwargs["litellm_call_id"] = uuid.uuid4().hex
        try:
            async with asyncio.timeout(request.timeout + _TIMEOUT_GRACE):
                raw = await self._litellm.acompletion(**kwargs)
        except TimeoutError:
            raise ModelTimeout(f"no reply within {request.timeout:g} s") from None
        except ModelError:
            raise
        except Exception as exc:
            raise map_error(exc, self._hidden) from None
        finally:
            sent, (finish, refusal) = wire.take(call_id)
        asked = {k: kwargs[k] for k in kwargs if k not in _PLUMBING}
        dropped = () if sent is None else wire.dropped(asked, sent)
        reply = self._response(raw, time.perf_counter() - started)
        recorded = None if sent is None else wire.recorded(sent)  # headers ride in some bodies
        refusal = refusal or reply.refusal
        return dataclasses.replace(
            reply, sent=recorded, dropped=dropped, refusal=refusal, provider_finish=finish
        )

    def _response(self, raw: Any, latency: float) -> ModelResponse:
        """The reply in ``raw``: its text, token counts (reasoning and cached ones too), cost
        and reasoning."""
        try:
            choice = raw.choices[0]
            text = choice.message.content or ""
        except (AttributeError, IndexError, TypeError) as exc:
            raise ServerError(f"reply has no message: {type(exc).__name__}") from None
        usage = getattr(raw, "usage", None)
        completion_details = getattr(usage, "completion_tokens_details", None)
        prompt_details = getattr(usage, "prompt_tokens_details", None)
        cost = None
        if self._priced:
            try:
                cost = float(
                    self._litellm.completion_cost(completion_response=raw, model=self.model)
                )
            except Exception:  # litellm raises many types for unmapped models: no price known
                cost = None
        reasoning = getattr(choice.message, "reasoning_content", None)
        extra = getattr(choice.message, "provider_specific_fields", None)
        refusal = extra.get("refusal") if isinstance(extra, dict) else None
        return ModelResponse(
            text=text,
            usage=Usage(  # all None without a usage
                input_tokens=getattr(usage, "prompt_tokens", None),
                output_tokens=getattr(usage, "completion_tokens", None),
                reasoning_tokens=getattr(completion_details, "reasoning_tokens", None),
                cached_tokens=getattr(prompt_details, "cached_tokens", None),
            ),
            cost=cost,
            latency=latency,
            model_id=str(getattr(raw, "model", "") or self.model),
            finish_reason=getattr(choice, "finish_reason", None),
            reasoning=str(reasoning)[:_REASONING_CAP] if reasoning else None,
            refusal=str(refusal) if refusal else None,
        )


_PLUMBING = frozenset(
    {"model", "messages", "timeout", "max_retries", "drop_params", "api_base", "litellm_call_id"}
)


def response_format(request: ModelRequest) -> dict[str, Any]:
    """The OpenAI-style ``response_format`` litellm translates for each provider that takes a
    response schema (and drops, reported as dropped, for one that does not)."""
    name = re.sub(r"[^A-Za-z0-9_-]", "_", f"{request.task}_answer")
    return {"type": "json_schema", "json_schema": {"name": name, "schema": request.response_schema}}
