"""Friendly model names and the provider ids litellm needs.

Users may type the names papers and leaderboards use (``claude-opus-4.7``); litellm needs the
provider's id (``anthropic/claude-opus-4-7``). Names not in the table pass through unchanged, and
``AdapterOptions.aliases`` (from ``--alias NAME=ID`` or the config) adds or overrides entries.
"""

from __future__ import annotations

from collections.abc import Mapping

ALIASES: dict[str, str] = {
    "claude-opus-4.7": "anthropic/claude-opus-4-7",
    "claude-opus-4.6": "anthropic/claude-opus-4-6",
    "claude-opus-4.5": "anthropic/claude-opus-4-5",
    "claude-sonnet-4.5": "anthropic/claude-sonnet-4-5",
    "claude-haiku-4.5": "anthropic/claude-haiku-4-5",
    "gpt-5.5": "openai/gpt-5.5",
    "gpt-5.4": "openai/gpt-5.4",
    "gpt-5.4-pro": "openai/gpt-5.4-pro",
    "gpt-5.2": "openai/gpt-5.2",
    "gpt-5.2-pro": "openai/gpt-5.2-pro",
    "gpt-5": "openai/gpt-5",
    "gpt-4o": "openai/gpt-4o",
    "gemini-3-flash-preview": "gemini/gemini-3-flash-preview",
    "gemini-3.1-pro-preview": "gemini/gemini-3.1-pro-preview",
    "gemini-2.5-pro": "gemini/gemini-2.5-pro",
    "gemini-2.5-flash": "gemini/gemini-2.5-flash",
    "qwen3.6-plus": "dashscope/qwen3.6-plus",
    "kimi-k2.5": "moonshot/kimi-k2.5",
}


def resolve(model: str, extra: Mapping[str, str] | None = None) -> str:
    """The litellm model id for ``model``: user aliases first, then the table, else unchanged."""
    if extra and model in extra:
        return extra[model]
    return ALIASES.get(model, model)
