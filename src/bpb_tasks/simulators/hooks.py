"""Registers the built-in simulators ``analytic`` and ``pymunk``."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registry import SimulatorInfo, lazy


@hookimpl
def bpb_simulators() -> Iterator[SimulatorInfo]:
    yield SimulatorInfo(
        "analytic",
        lazy("bpb_tasks.simulators.analytic.engine:AnalyticSimulator"),
        "Exact event-driven billiards (float64; precision=50 for mpmath)",
        family="billiards",
    )
    yield SimulatorInfo(
        "pymunk",
        lazy("bpb_tasks.simulators.pymunk_sim:PymunkSimulator"),
        "Fixed-step Chipmunk2D (pymunk) with option dt (default 1e-3 s)",
        family="billiards",
    )
