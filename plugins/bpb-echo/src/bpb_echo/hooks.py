"""Registration: cheap to import, the adapter module is loaded only when used."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core import AdapterInfo, hookimpl, lazy


@hookimpl
def bpb_model_adapters() -> Iterator[AdapterInfo]:
    yield AdapterInfo(
        "echo",
        lazy("bpb_echo.adapter:make_adapter"),
        "Example plugin: replies with the prompt text (its example answer parses)",
        models=("prompt", "upper"),
    )
