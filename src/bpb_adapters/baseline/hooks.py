"""Registers the ``baseline`` adapter family."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registry import AdapterInfo, lazy


@hookimpl
def bpb_model_adapters() -> Iterator[AdapterInfo]:
    yield AdapterInfo(
        "baseline",
        lazy("bpb_adapters.baseline.adapter:make_adapter"),
        "Offline reference answers: stasis, straight, random, oracle; vision on request",
        models=("stasis", "straight", "random", "oracle"),
        offline=True,
        catalog=lazy("bpb_adapters.baseline.hooks:on_request"),
    )


def on_request() -> list[tuple[str, str]]:
    """Baselines listed by ``bpb list adapters`` but not run by default (slower)."""
    return [
        (
            "vision",
            "reads the scene from the input image and prompt (perception), then simulates it; "
            "records its perception error (run on request)",
        )
    ]
