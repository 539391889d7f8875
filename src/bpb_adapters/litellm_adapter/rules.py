"""Provider rules: options a provider rejects together are never sent together, and every
option bpb rewrites to obey a rule is named in the run's settings and label.

litellm passes most arguments through and leaves the provider to refuse a bad mix, or rewrites
one on its own without saying so. These rules run before litellm sees the arguments, from the
model's entry in litellm's bundled model map; each is listed with its source in
docs/providers.md:

- Anthropic's extended thinking takes no temperature but 1, no ``top_k`` and a ``top_p`` of
  0.95 to 1 ("Thinking isn't compatible with temperature or top_k modifications"). With
  thinking on (``thinking``, or a ``reasoning_effort``, which litellm maps onto thinking) the
  run's temperature is not sent and the run records ``temperature: provider default
  (thinking)``; such an argument given explicitly is refused before any call.
- A Claude model that takes adaptive thinking only (litellm's map: ``supports_adaptive_thinking``
  without ``supports_legacy_thinking``, i.e. Opus 4.7) rejects ``thinking.type = "enabled"``
  with a budget; litellm would turn the budget into an effort silently. bpb makes the same
  translation itself, with litellm's thresholds, and names it: ``thinking=8000 as effort=high``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from bpb_core.errors import BadInput

# litellm 1.106.2's budget -> effort thresholds for adaptive-only Claude models (lowest first)
_EFFORT_FROM_BUDGET = ((2048, "medium"), (4096, "high"), (8192, "xhigh"))
TEMPERATURE_NOTE = "temperature: provider default (thinking)"


@dataclass(frozen=True)
class Plan:
    """What an adapter sends once the rules are applied.

    Attributes:
        args: The model arguments handed to litellm.
        temperature: Whether the run's temperature is sent.
        notes: Each rewrite, for run.json (``temperature: provider default (thinking)``).
        tags: The same, short, for the run's label (``thinking=8000 as effort=high``).
        replaced: Requested arguments a tag stands for in the label (``thinking``).
    """

    args: dict[str, Any]
    temperature: bool = True
    notes: tuple[str, ...] = ()
    tags: tuple[str, ...] = ()
    replaced: frozenset[str] = frozenset()


def _anthropic(model: str, entry: Mapping[str, Any]) -> bool:
    return model.startswith("anthropic/") or entry.get("litellm_provider") == "anthropic"


def _effort(budget: int, entry: Mapping[str, Any]) -> str:
    effort = "low"
    for floor, level in _EFFORT_FROM_BUDGET:
        if budget >= floor and (level != "xhigh" or entry.get("supports_xhigh_reasoning_effort")):
            effort = level
    return effort


def _budget_as_effort(model: str, args: dict[str, Any], entry: Mapping[str, Any]) -> Plan:
    thinking = args.get("thinking")
    adaptive_only = entry.get("supports_adaptive_thinking") and not entry.get(
        "supports_legacy_thinking"
    )
    if not (adaptive_only and isinstance(thinking, Mapping) and thinking.get("type") == "enabled"):
        return Plan(args)
    if "reasoning_effort" in args:
        raise BadInput(
            f"model arguments thinking and reasoning_effort: {model} takes one of them, not both"
        )
    budget = thinking.get("budget_tokens")
    if not isinstance(budget, int) or isinstance(budget, bool):
        raise BadInput(f"model argument thinking.budget_tokens: expected a number, got {budget!r}")
    effort = _effort(budget, entry)
    sent = {k: v for k, v in args.items() if k != "thinking"} | {"reasoning_effort": effort}
    note = (
        f"thinking.budget_tokens: {budget} sent as reasoning_effort {effort!r} ({model} takes "
        "adaptive thinking only)"
    )
    tag = f"thinking={budget} as effort={effort}"
    return Plan(sent, notes=(note,), tags=(tag,), replaced=frozenset({"thinking"}))


def _thinking_on(args: Mapping[str, Any]) -> bool:
    thinking = args.get("thinking")
    if isinstance(thinking, Mapping) and thinking.get("type") in ("enabled", "adaptive"):
        return True
    return args.get("reasoning_effort") not in (None, "none")


def _sampling_with_thinking(args: Mapping[str, Any]) -> None:
    temperature, top_p = args.get("temperature", 1), args.get("top_p", 1)
    if temperature != 1:
        raise BadInput(
            f"model argument temperature: Anthropic's extended thinking takes no temperature "
            f"but 1, got {temperature!r} (leave it out: the provider's default is used)"
        )
    if "top_k" in args:
        raise BadInput("model argument top_k: Anthropic's extended thinking takes no top_k")
    if not (isinstance(top_p, int | float) and 0.95 <= top_p <= 1):
        raise BadInput(
            f"model argument top_p: Anthropic's extended thinking takes 0.95 to 1, got {top_p!r}"
        )


def plan(model: str, args: Mapping[str, Any], entry: Mapping[str, Any]) -> Plan:
    """Apply the provider rules to the model arguments of ``model``.

    Args:
        model: The litellm model id.
        args: The model arguments the user gave.
        entry: The model's entry in litellm's model map (empty when it has none).

    Raises:
        BadInput: An argument the provider rejects in this combination (one line naming it).
    """
    if not _anthropic(model, entry):
        return Plan(dict(args))
    translated = _budget_as_effort(model, dict(args), entry)
    if not _thinking_on(translated.args):
        return translated
    _sampling_with_thinking(translated.args)
    if "temperature" in translated.args:  # 1, given explicitly: sent as asked
        return translated
    return Plan(
        translated.args,
        temperature=False,
        notes=(*translated.notes, TEMPERATURE_NOTE),
        tags=(*translated.tags, "temp=default"),
        replaced=translated.replaced,
    )
