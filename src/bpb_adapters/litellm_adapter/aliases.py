"""Friendly model names, the provider ids litellm needs, and what each provider expects.

Users may type the names papers and leaderboards use (``claude-opus-4.7``); litellm needs the
provider's id (``anthropic/claude-opus-4-7``). Names not in the table pass through unchanged, and
``AdapterOptions.aliases`` (from ``--alias NAME=ID`` or the config) adds or overrides entries.
:data:`PROVIDERS` says which environment variable holds each provider's key and what
``api_base`` means for it (litellm appends a different path per provider).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Provider:
    """A provider as bpb users meet it.

    Attributes:
        env: Environment variables litellm reads the key from (any one is enough).
        api_base: What ``api_base`` must point at (litellm appends the rest).
    """

    env: tuple[str, ...]
    api_base: str


PROVIDERS: dict[str, Provider] = {
    "openai": Provider(("OPENAI_API_KEY",), "up to /v1; + /chat/completions or /responses"),
    "anthropic": Provider(("ANTHROPIC_API_KEY",), "the host root; + /v1/messages"),
    "gemini": Provider(("GEMINI_API_KEY", "GOOGLE_API_KEY"), "up to /v1beta; + /models/..."),
    "dashscope": Provider(("DASHSCOPE_API_KEY",), "up to /compatible-mode/v1; + /chat/completions"),
    "moonshot": Provider(("MOONSHOT_API_KEY",), "up to /v1; + /chat/completions"),
    "volcengine": Provider(("VOLCENGINE_API_KEY",), "up to /api/v3; + /chat/completions"),
}

# The models of the paper, in its order: (alias, litellm id).
PAPER_MODELS: tuple[tuple[str, str], ...] = (
    ("gpt-5.2", "openai/gpt-5.2"),
    ("gpt-5.2-pro", "openai/gpt-5.2-pro"),
    ("gpt-5.4", "openai/gpt-5.4"),
    ("gpt-5.4-pro", "openai/gpt-5.4-pro"),
    ("gpt-5.5", "openai/gpt-5.5"),
    ("gpt-5.5-pro", "openai/gpt-5.5-pro"),
    ("claude-opus-4.5", "anthropic/claude-opus-4-5"),
    ("claude-opus-4.6", "anthropic/claude-opus-4-6"),
    ("claude-opus-4.7", "anthropic/claude-opus-4-7"),
    ("gemini-3-flash-preview", "gemini/gemini-3-flash-preview"),
    ("gemini-3.1-pro-preview", "gemini/gemini-3.1-pro-preview"),
    ("qwen3-vl-plus", "dashscope/qwen3-vl-plus"),
    ("qwen3.5-plus", "dashscope/qwen3.5-plus"),
    ("qwen3.6-plus", "dashscope/qwen3.6-plus"),
    ("kimi-k2.5", "moonshot/kimi-k2.5"),
    ("doubao-seed-1.8", "volcengine/doubao-seed-1-8-251228"),
    ("doubao-seed-2.0-pro", "volcengine/doubao-seed-2-0-pro-260215"),
)

ALIASES: dict[str, str] = {
    **dict(PAPER_MODELS),
    "claude-sonnet-4.5": "anthropic/claude-sonnet-4-5",
    "claude-haiku-4.5": "anthropic/claude-haiku-4-5",
    "gpt-5": "openai/gpt-5",
    "gpt-4o": "openai/gpt-4o",
    "gemini-2.5-pro": "gemini/gemini-2.5-pro",
    "gemini-2.5-flash": "gemini/gemini-2.5-flash",
}


def resolve(model: str, extra: Mapping[str, str] | None = None) -> str:
    """The litellm model id for ``model``: user aliases first, then the table, else unchanged."""
    if extra and model in extra:
        return extra[model]
    return ALIASES.get(model, model)


def missing_key(model: str, args: Mapping[str, Any]) -> str | None:
    """A one-line complaint when ``model``'s provider is in :data:`PROVIDERS` and none of its
    key variables is set (checked without importing litellm), else ``None``."""
    provider = PROVIDERS.get(model.split("/", 1)[0]) if "/" in model else None
    if provider is None or "api_key" in args or any(os.environ.get(v) for v in provider.env):
        return None
    names = " or ".join(provider.env)
    return f"{model}: environment variable {names} is not set (the provider's API key)"
