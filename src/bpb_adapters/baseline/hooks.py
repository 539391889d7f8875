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
        (
            "offline reference answers: stasis says nothing happens (no contact, every ball "
            "stays), a floor that scores high wherever most true answers are 'no', as on Q1, "
            "where most balls are never touched; straight rolls the cue ball alone (friction, wall "
            "bounces, no other ball); random guesses; oracle answers the ground truth (the "
            "ceiling); vision "
            "(on request) reads the image, then simulates"
        ),
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
