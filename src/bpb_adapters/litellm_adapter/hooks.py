"""Registers the ``litellm`` adapter family (litellm itself is imported only when used)."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registry import AdapterInfo, lazy


@hookimpl
def bpb_model_adapters() -> Iterator[AdapterInfo]:
    yield AdapterInfo(
        "litellm",
        lazy("bpb_adapters.litellm_adapter.adapter:LiteLLMAdapter"),
        "Any litellm model string (openai/..., anthropic/..., gemini/...) or a known alias",
        catalog=lazy("bpb_adapters.litellm_adapter.aliases:catalog"),
    )
