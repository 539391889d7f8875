"""Checks before the first call: the provider is known, its key is set, its modules import.

Each failure is one line naming what to fix (the environment variable, the missing module), so
``bpb run`` can stop with exit 2 before any request is sent.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from bpb_adapters.litellm_adapter.aliases import missing_key

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


def _unknown(model: str) -> str:
    return (
        f"litellm knows no provider for {model!r}: write PROVIDER/MODEL (openai/..., "
        "anthropic/..., gemini/..., volcengine/...) or use an alias from 'bpb list adapters'"
    )


def quick_preflight(model: str, api_base: str | None, args: Mapping[str, Any]) -> str | None:
    """The checks that need no litellm import: a bare name litellm's map does not hold (and no
    ``api_base`` to route by) has no provider; a known provider's key variable must be set."""
    names = bundled_map()
    if "/" not in model and api_base is None and names and model not in names:
        return _unknown(model)
    entry = names.get(model) or names.get(model.split("/", 1)[-1]) or {}
    route = "responses" if entry.get("mode") == "responses" else "chat"
    return missing_key(model, args) or _missing_module(model, route)


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


def route_of(litellm: Any, model: str, provider: str) -> str:
    """``responses`` when litellm sends ``model`` through the OpenAI Responses API."""
    if provider != "openai":
        return "chat"
    try:
        info = litellm.main.responses_api_bridge_check(model.split("/", 1)[-1], provider)[0]
    except Exception:  # an unmapped model goes through chat completions
        return "chat"
    return "responses" if info.get("mode") == "responses" else "chat"


def missing_keys(litellm: Any, model: str, api_base: str | None) -> list[str]:
    """Environment variables litellm needs for ``model`` and does not find."""
    try:
        found = litellm.validate_environment(model=model, api_base=api_base)
    except Exception:  # litellm could not tell: let the first call say
        return []
    return [str(k) for k in found.get("missing_keys") or []]


def preflight(
    litellm: Any, model: str, api_base: str | None, model_args: Mapping[str, Any]
) -> str | None:
    """``None`` when calls to ``model`` may be sent, else one line saying what is wrong."""
    provider = provider_of(litellm, model, api_base)
    if provider is None:
        return _unknown(model)
    if "api_key" not in model_args:
        missing = missing_keys(litellm, model, api_base)
        if missing:
            names = " or ".join(missing)
            return f"{model}: environment variable {names} is not set (the {provider} API key)"
    return _missing_module(model, route_of(litellm, model, provider))
