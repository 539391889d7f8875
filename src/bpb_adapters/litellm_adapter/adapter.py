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
import importlib
import os
import time
from collections import OrderedDict
from collections.abc import Mapping
from typing import Any

from bpb_adapters.litellm_adapter.aliases import resolve
from bpb_adapters.litellm_adapter.errors import map_error
from bpb_core.errors import ModelError, ModelTimeout, ServerError
from bpb_core.model_calls import (
    AdapterOptions,
    ImagePart,
    Message,
    ModelRequest,
    ModelResponse,
    TextPart,
    Usage,
)

_TIMEOUT_GRACE = 5.0  # our own watchdog beyond the HTTP timeout, in case a layer ignores it


def _import_litellm() -> Any:
    # Always the bundled price map: a run must never reach out for prices, whatever the shell says.
    os.environ["LITELLM_LOCAL_MODEL_COST_MAP"] = "True"
    litellm: Any = importlib.import_module("litellm")
    litellm.suppress_debug_info = True
    litellm.set_verbose = False
    litellm.telemetry = False
    return litellm


class _DataUris:
    """Base64 data URIs of recent images, so an image shared by a scene's tasks is encoded once."""

    def __init__(self, size: int = 256) -> None:
        self._size = size
        self._cache: OrderedDict[int, tuple[bytes, str]] = OrderedDict()

    def get(self, part: ImagePart) -> str:
        key = id(part.data)
        hit = self._cache.get(key)
        if hit is not None and hit[0] is part.data:
            self._cache.move_to_end(key)
            return hit[1]
        uri = f"data:{part.media_type};base64,{base64.b64encode(part.data).decode('ascii')}"
        self._cache[key] = (part.data, uri)
        if len(self._cache) > self._size:
            self._cache.popitem(last=False)
        return uri


class LiteLLMAdapter:
    """Talks to one model through litellm.

    Args:
        model: The name the user gave (an alias or a litellm model string).
        options: ``api_base``, price overrides and aliases.
    """

    def __init__(self, model: str, options: AdapterOptions) -> None:
        self.name = f"litellm:{model}"
        self.model = resolve(model, options.aliases)
        self._requested = model
        self._api_base = options.api_base
        self._prices = options.prices
        self._litellm = _import_litellm()
        self._uris = _DataUris()

    def _content(self, message: Message) -> str | list[dict[str, Any]]:
        if all(isinstance(p, TextPart) for p in message.parts):
            return "\n\n".join(p.text for p in message.parts if isinstance(p, TextPart))
        parts: list[dict[str, Any]] = []
        for part in message.parts:
            if isinstance(part, TextPart):
                parts.append({"type": "text", "text": part.text})
            else:
                parts.append({"type": "image_url", "image_url": {"url": self._uris.get(part)}})
        return parts

    def _kwargs(self, request: ModelRequest) -> dict[str, Any]:
        kwargs: dict[str, Any] = {
            "model": self.model,
            "messages": [{"role": m.role, "content": self._content(m)} for m in request.messages],
            "temperature": request.temperature,
            "timeout": request.timeout,
            "max_retries": 0,
            "drop_params": True,
        }
        if request.max_tokens is not None:
            kwargs["max_tokens"] = request.max_tokens
        if self._api_base:
            kwargs["api_base"] = self._api_base
        return kwargs

    async def complete(self, request: ModelRequest) -> ModelResponse:
        """Send ``request``; raise a :mod:`bpb_core.errors` model error on failure."""
        started = time.perf_counter()
        try:
            async with asyncio.timeout(request.timeout + _TIMEOUT_GRACE):
                raw = await self._litellm.acompletion(**self._kwargs(request))
        except TimeoutError:
            raise ModelTimeout(f"no reply within {request.timeout:g} s") from None
        except ModelError:
            raise
        except Exception as exc:
            raise map_error(exc) from None
        return self._response(raw, time.perf_counter() - started)

    def _response(self, raw: Any, latency: float) -> ModelResponse:
        try:
            choice = raw.choices[0]
            text = choice.message.content or ""
        except (AttributeError, IndexError, TypeError) as exc:
            raise ServerError(f"reply has no message: {type(exc).__name__}") from None
        usage = usage_of(raw)
        return ModelResponse(
            text=text,
            usage=usage,
            cost=self._cost(raw, usage),
            latency=latency,
            model_id=str(getattr(raw, "model", "") or self.model),
            finish_reason=getattr(choice, "finish_reason", None),
        )

    def _cost(self, raw: Any, usage: Usage) -> float | None:
        override = self._prices.get(self._requested) or self._prices.get(self.model)
        if override is not None:
            return price(override, usage)
        if not _has_price(self._litellm.model_cost, self.model):
            return None
        try:
            return float(self._litellm.completion_cost(completion_response=raw, model=self.model))
        except Exception:  # litellm raises many types for unmapped models: no price known
            return None


def _has_price(table: Mapping[str, Any], model: str) -> bool:
    for key in (model, model.split("/", 1)[-1]):
        entry = table.get(key)
        if entry and entry.get("input_cost_per_token") is not None:
            return True
    return False


def price(override: Mapping[str, float], usage: Usage) -> float:
    """Cost in USD from per-token prices ``{"input": .., "output": ..}``."""
    return (usage.input_tokens or 0) * override.get("input", 0.0) + (
        usage.output_tokens or 0
    ) * override.get("output", 0.0)


def usage_of(raw: Any) -> Usage:
    """Token counts from a litellm response, including reasoning and cached tokens."""
    usage = getattr(raw, "usage", None)
    if usage is None:
        return Usage()
    completion_details = getattr(usage, "completion_tokens_details", None)
    prompt_details = getattr(usage, "prompt_tokens_details", None)
    return Usage(
        input_tokens=getattr(usage, "prompt_tokens", None),
        output_tokens=getattr(usage, "completion_tokens", None),
        reasoning_tokens=getattr(completion_details, "reasoning_tokens", None),
        cached_tokens=getattr(prompt_details, "cached_tokens", None),
    )


def make_adapter(model: str, options: AdapterOptions) -> LiteLLMAdapter:
    """Build ``litellm:<model>``."""
    return LiteLLMAdapter(model, options)
