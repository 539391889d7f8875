"""The ``bpb`` entry point of bpb-tiny: registers the slider family, its simulator, task,
scorer and diagnostic.

Only records are built here; every ``load`` is :func:`~bpb_core.registry.lazy`, so listing
plugins imports none of pandas, Pillow or matplotlib.
"""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registry import (
    DiagnosticInfo,
    SceneFamilyInfo,
    ScorerInfo,
    SimulatorInfo,
    TaskInfo,
    lazy,
)


@hookimpl
def bpb_scene_families() -> Iterator[SceneFamilyInfo]:
    yield SceneFamilyInfo(
        "slider",
        lazy("bpb_tiny.family:SliderFamily"),
        "One puck on a 1-D track with friction and two elastic end walls",
    )


@hookimpl
def bpb_simulators() -> Iterator[SimulatorInfo]:
    yield SimulatorInfo(
        "slider-exact",
        lazy("bpb_tiny.physics:SliderExact"),
        "Closed-form slider motion (float64)",
        family="slider",
    )


@hookimpl
def bpb_eval_tasks() -> Iterator[TaskInfo]:
    yield TaskInfo(
        "slider_stop",
        lazy("bpb_tiny.task:SliderStopTask"),
        "Where the puck is at t and how many wall hits by then",
        family="slider",
        default=True,
        title="Slider stop",
    )


@hookimpl
def bpb_scorers() -> Iterator[ScorerInfo]:
    yield ScorerInfo(
        "slider_stop",
        lazy("bpb_tiny.scorer:SliderStopScorer"),
        "Position within 2% of the track, exact wall-hit count",
        task="slider_stop",
    )


@hookimpl
def bpb_diagnostics() -> Iterator[DiagnosticInfo]:
    yield DiagnosticInfo(
        "slider_errors",
        lazy("bpb_tiny.diagnostics:SliderErrors"),
        "Slider position error and wall-hit count bias per run",
        tasks=("slider_stop",),
    )
