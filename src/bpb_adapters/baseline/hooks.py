"""Registers the ``baseline`` adapter family."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registration import AdapterInfo, lazy


@hookimpl
def bpb_model_adapters() -> Iterator[AdapterInfo]:
    yield AdapterInfo(
        "baseline",
        lazy("bpb_adapters.baseline.adapter:make_adapter"),
        "Offline reference answers, no network: stasis, straight, random, oracle "
        "(by default); vision (reads the image, then simulates; on request)",
        models=("stasis", "straight", "random", "oracle"),
        offline=True,
    )
