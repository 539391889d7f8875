"""Model names and providers: friendly aliases, the provider ids litellm needs, what each
provider expects, the checks before the first call and the catalog ``bpb list adapters`` shows.

Users may type the names papers and leaderboards use (``claude-opus-4.7``); litellm needs the
provider's id (``anthropic/claude-opus-4-7``). Names not in the table pass through unchanged, and
``AdapterOptions.aliases`` (from ``--alias NAME=ID`` or the config) adds or overrides entries.
:data:`PROVIDERS` says which environment variable holds each provider's key and what
``api_base`` means for it (litellm appends a different path per provider).

The checks before the first call (the provider is known, its key is set, its modules import)
each fail with one line naming what to fix (the environment variable, the missing module), so
``bpb run`` can stop with exit 2 before any request is sent.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bpb_adapters.litellm_adapter.prices import has_price


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


# Modules a litellm route imports only when it is first used.
_ROUTE_MODULES: dict[str, tuple[str, ...]] = {"responses": ("mcp.types",)}


@functools.cache
def bundled_map() -> dict[str, Any]:
    """litellm's bundled price map, read without importing litellm (which takes seconds)."""
    spec = importlib.util.find_spec("litellm")
    if spec is None or not spec.submodule_search_locations:
        return {}
    path = Path(next(iter(spec.submodule_search_locations)))
    try:
        table = json.loads((path / "model_prices_and_context_window_backup.json").read_bytes())
    except (OSError, ValueError):
        return {}
    return table if isinstance(table, dict) else {}


def map_entry(model: str) -> dict[str, Any]:
    """The entry of ``model`` (a litellm id, with or without its provider) in the bundled map,
    empty when it has none."""
    table = bundled_map()
    entry = table.get(model) or table.get(model.split("/", 1)[-1]) or {}
    return entry if isinstance(entry, dict) else {}


def _unknown(model: str) -> str:
    return (
        f"litellm knows no provider for {model!r}: write PROVIDER/MODEL (openai/..., "
        "anthropic/..., gemini/..., volcengine/...) or use an alias from 'bpb list adapters'"
    )


def quick_preflight(model: str, api_base: str | None, args: Mapping[str, Any]) -> str | None:
    """The checks that need no litellm import: a bare name litellm's map does not hold (and no
    ``api_base`` to route by) has no provider; a key variable of a provider in
    :data:`PROVIDERS` must be set."""
    table = bundled_map()
    if "/" not in model and api_base is None and table and model not in table:
        return _unknown(model)
    provider = PROVIDERS.get(model.split("/", 1)[0]) if "/" in model else None
    if provider and "api_key" not in args and not any(os.environ.get(v) for v in provider.env):
        names = " or ".join(provider.env)
        return f"{model}: environment variable {names} is not set (the provider's API key)"
    route = "responses" if map_entry(model).get("mode") == "responses" else "chat"
    return _missing_module(model, route)


def _missing_module(model: str, route: str) -> str | None:
    for module in _ROUTE_MODULES.get(route, ()):
        try:
            importlib.import_module(module)
        except ImportError as exc:
            return (
                f"{model}: litellm's {route} route needs the module {exc.name or module!r}, "
                "which is not installed (pip install 'bpb[litellm]')"
            )
    return None


def provider_of(litellm: Any, model: str, api_base: str | None = None) -> str | None:
    """The litellm provider id of ``model`` (``None`` when litellm cannot route it)."""
    try:
        provider = litellm.get_llm_provider(model=model, api_base=api_base)[1]
    except Exception:  # litellm raises BadRequestError and friends for an unknown provider
        return None
    return str(provider) if provider else None


def preflight(
    litellm: Any, model: str, api_base: str | None, model_args: Mapping[str, Any]
) -> str | None:
    """``None`` when calls to ``model`` may be sent, else one line saying what is wrong: the
    provider unknown, a key variable litellm needs not set, a module of the route (``responses``
    when litellm sends ``model`` through the OpenAI Responses API, else ``chat``) missing."""
    provider = provider_of(litellm, model, api_base)
    if provider is None:
        return _unknown(model)
    if "api_key" not in model_args:
        try:
            found = litellm.validate_environment(model=model, api_base=api_base)
        except Exception:  # litellm could not tell: let the first call say
            found = {}
        missing = [str(k) for k in found.get("missing_keys") or []]
        if missing:
            names = " or ".join(missing)
            return f"{model}: environment variable {names} is not set (the {provider} API key)"
    route = "chat"
    if provider == "openai":
        try:
            info = litellm.main.responses_api_bridge_check(model.split("/", 1)[-1], provider)[0]
        except Exception:  # an unmapped model goes through chat completions
            info = {}
        route = "responses" if info.get("mode") == "responses" else "chat"
    return _missing_module(model, route)


def catalog() -> list[tuple[str, str]]:
    """``(alias, description)`` for every alias of the table, in its order."""
    table = bundled_map()
    rows = []
    for alias, model in ALIASES.items():
        provider_id = model.split("/", 1)[0]
        provider = PROVIDERS.get(provider_id)
        price = "price known" if has_price(table, model) else "no price (give one: --prices)"
        where = "" if provider is None else f"; key {' or '.join(provider.env)}"
        base = "" if provider is None else f"; api_base {provider.api_base}"
        rows.append((alias, f"{model} (provider {provider_id}{where}; {price}{base})"))
    return rows
