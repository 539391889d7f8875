"""Price overrides, registered with litellm so its own cost function applies them.

An override is USD per token: ``{"input": .., "output": .., "cache_read": .., "reasoning": ..}``
(``cache_read`` and ``reasoning`` optional; cached input costs ``input`` unless ``cache_read``
is given, reasoning tokens ``output`` unless ``reasoning`` is). litellm then prices cached input
and reasoning output exactly as it does for models in its bundled map. An override applies to
the model id process-wide (litellm keeps one map).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from bpb_core.model_calls import known_cost

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
