"""Prices: overrides registered with litellm, the input tokens and cost of a request before it
is sent (``bpb run --dry-run``), and the most its output may cost (``--max-cost`` reserves it).

An override is USD per token: ``{"input": .., "output": .., "cache_read": .., "reasoning": ..}``
(``cache_read`` and ``reasoning`` optional; cached input costs ``input`` unless ``cache_read``
is given, reasoning tokens ``output`` unless ``reasoning`` is). litellm then prices cached input
and reasoning output exactly as it does for models in its bundled map. An override applies to
the model id process-wide (litellm keeps one map).

Text is counted with litellm's token counter (the provider's tokenizer where litellm has one,
else tiktoken's). Images follow each provider's documented rule:

- OpenAI and OpenAI-compatible providers: 85 + 170 per 512-pixel tile after scaling to fit
  2048 x 768 (high detail);
- Anthropic: width x height / 750 after scaling the long edge to at most 1568 pixels;
- Gemini: 258 for an image within 384 x 384, else 258 per 768 x 768 tile.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Mapping
from typing import Any

from bpb_core.model_calls import ImagePart, Message, TextPart, known_cost
from bpb_core.runner.dry_run import image_tokens as openai_image_tokens

_FIELDS = {
    "input": "input_cost_per_token",
    "output": "output_cost_per_token",
    "cache_read": "cache_read_input_token_cost",
    "cache_write": "cache_creation_input_token_cost",
    "reasoning": "output_cost_per_reasoning_token",
}


def litellm_entry(override: Mapping[str, float], provider: str | None) -> dict[str, Any]:
    """The litellm model-map entry for a bpb price override.

    Raises:
        ValueError: An unknown key or a price that is not a finite number >= 0.
    """
    entry: dict[str, Any] = {"mode": "chat"}
    if provider:
        entry["litellm_provider"] = provider
    for key, value in override.items():
        if key not in _FIELDS:
            raise ValueError(f"unknown price {key!r}; known: {', '.join(_FIELDS)}")
        if known_cost(value) is None:  # a NaN price would void --max-cost
            raise ValueError(f"price {key!r} must be a finite number >= 0, got {value!r}")
        entry[_FIELDS[key]] = float(value)
    if "input" in override and "cache_read" not in override:
        # litellm merges into the bundled entry: never keep its cache price beside a new input
        entry[_FIELDS["cache_read"]] = float(override["input"])
    return entry


def has_price(table: Mapping[str, Any], model: str) -> bool:
    """Whether litellm's map prices ``model`` (with or without its provider prefix)."""
    for key in (model, model.split("/", 1)[-1]):
        entry = table.get(key)
        if entry and entry.get("input_cost_per_token") is not None:
            return True
    return False


def register(litellm: Any, model: str, provider: str | None, override: Mapping[str, float]) -> None:
    """Make litellm price ``model`` by ``override`` (both with and without the prefix)."""
    entry = litellm_entry(override, provider)
    bare = model.split("/", 1)[-1]
    litellm.register_model({model: dict(entry), bare: dict(entry)})


def image_tokens(provider: str | None, png: bytes) -> int:
    """Tokens one PNG costs with ``provider`` (OpenAI's rule for providers without their own)."""
    unreadable = len(png) < 24 or png[:8] != b"\x89PNG\r\n\x1a\n"
    if unreadable or provider not in ("anthropic", "gemini"):
        return openai_image_tokens(png)
    width, height = (int(v) for v in struct.unpack(">II", png[16:24]))
    if provider == "anthropic":
        scale = min(1.0, 1568 / max(width, height))
        return max(1, math.ceil(width * scale * height * scale / 750))
    if width <= 384 and height <= 384:
        return 258
    return 258 * math.ceil(width / 768) * math.ceil(height / 768)


def estimate(
    litellm: Any, model: str, provider: str | None, messages: tuple[Message, ...], priced: bool
) -> tuple[int, float | None]:
    """Input tokens of ``messages`` and their input cost (``None`` without a price)."""
    text = "\n".join(p.text for m in messages for p in m.parts if isinstance(p, TextPart))
    try:  # litellm's counter for the model
        tokens = int(litellm.token_counter(model=model, text=text))
    except Exception:  # an unmapped tokenizer: the rough rule, characters / 4
        tokens = len(text) // 4
    tokens += sum(
        image_tokens(provider, p.data)
        for m in messages
        for p in m.parts
        if isinstance(p, ImagePart)
    )
    if not priced:
        return tokens, None
    try:
        prompt_cost, _ = litellm.cost_per_token(model=model, prompt_tokens=tokens)
    except Exception:  # litellm raises many types for unmapped models: no price known
        return tokens, None
    return tokens, float(prompt_cost)


_LIMIT_ARGS = ("max_tokens", "max_completion_tokens", "max_output_tokens")


def output_limit(
    litellm: Any, model: str, asked: int | None, args: Mapping[str, Any]
) -> tuple[int | None, str]:
    """The most output tokens one call may bill, and where that figure comes from: the
    model's own arguments (they win over the run's ``max_tokens``; with several, the largest),
    else the run's ``max_tokens``, else litellm's model info for the model."""
    given = {k: args[k] for k in _LIMIT_ARGS if isinstance(args.get(k), int)}
    if asked is not None and "max_tokens" not in given:
        given["--max-tokens"] = asked
    if given:
        key = max(given, key=lambda k: given[k])
        return given[key], f"{key} {given[key]:,}" + ("" if key.startswith("-") else " (args)")
    try:
        info = litellm.get_model_info(model)
    except Exception:  # litellm raises many types for unmapped models: no limit known
        return None, "no output limit known"
    limit = info.get("max_output_tokens") or info.get("max_tokens")
    if not isinstance(limit, int) or limit <= 0:
        return None, "no output limit known"
    return limit, f"the model's output limit {limit:,} (litellm model info)"


def output_price(litellm: Any, model: str) -> float | None:
    """USD per output token: the dearer of litellm's output and reasoning prices for the model
    (overrides included), or ``None`` without one."""
    try:
        info = litellm.get_model_info(model)
    except Exception:  # litellm raises many types for unmapped models: no price known
        return None
    found = [known_cost(info.get(k)) for k in ("output_cost_per_token", _FIELDS["reasoning"])]
    known = [p for p in found if p is not None]
    return max(known) if known else None
