"""What the real APIs reject, so that the fake server rejects it too.

Each rule and its source is listed in docs/providers.md ("Provider rules"). A rejected request
gets the provider's HTTP 400 error body; it is recorded (``GET /requests``) like any other.
"""

from __future__ import annotations

from typing import Any

from aiohttp import web

# Claude models that take adaptive thinking only: litellm's model map gives them
# supports_adaptive_thinking without supports_legacy_thinking.
_ADAPTIVE_ONLY = ("claude-opus-4-7",)
_MIN_BUDGET = 1024


def _thinking_rules(body: dict[str, Any], thinking: dict[str, Any]) -> str | None:
    temperature, top_p = body.get("temperature", 1), body.get("top_p", 1)
    if temperature != 1:
        return "`temperature` may only be set to 1 when thinking is enabled"
    if "top_k" in body:
        return "`top_k` is not supported when thinking is enabled"
    if not 0.95 <= top_p <= 1:
        return "`top_p` must be between 0.95 and 1 when thinking is enabled"
    if thinking.get("type") != "enabled":
        return None
    if str(body.get("model", "")) in _ADAPTIVE_ONLY:
        return "thinking.type.enabled is not supported for this model; use thinking.type.adaptive"
    budget = thinking.get("budget_tokens")
    if not isinstance(budget, int) or budget < _MIN_BUDGET:
        return f"thinking.enabled.budget_tokens: must be at least {_MIN_BUDGET}"
    if budget >= body["max_tokens"]:
        return "`max_tokens` must be greater than `thinking.budget_tokens`"
    return None


def anthropic_rejection(body: dict[str, Any]) -> str | None:
    """Why Anthropic's Messages API would refuse ``body``, or ``None``."""
    if not isinstance(body.get("max_tokens"), int):
        return "max_tokens: Field required"
    thinking = body.get("thinking")
    if isinstance(thinking, dict) and thinking.get("type") in ("enabled", "adaptive"):
        return _thinking_rules(body, thinking)
    return None


def anthropic_error(message: str) -> web.Response:
    """Anthropic's error body for an invalid request."""
    error = {"type": "invalid_request_error", "message": message}
    return web.json_response({"type": "error", "error": error}, status=400)
