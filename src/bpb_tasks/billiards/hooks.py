"""Registers the ``billiards`` scene family."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registry import SceneFamilyInfo, lazy


@hookimpl
def bpb_scene_families() -> Iterator[SceneFamilyInfo]:
    yield SceneFamilyInfo(
        "billiards",
        lazy("bpb_tasks.billiards.family:BilliardsFamily"),
        "7 balls on a 2 m x 1 m table with 6 pockets; only the cue ball moves",
        default=True,
    )
