"""Registers task q3 with its scorer and diagnostics."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registry import DiagnosticInfo, ScorerInfo, TaskInfo, lazy


@hookimpl
def bpb_eval_tasks() -> Iterator[TaskInfo]:
    yield TaskInfo(
        "q3",
        lazy("bpb_tasks.q3.task:Q3Task"),
        "Q3: every ball's position at the horizon (null if pocketed)",
        family="billiards",
        default=True,
        title="Q3 final positions",
    )


@hookimpl
def bpb_scorers() -> Iterator[ScorerInfo]:
    yield ScorerInfo(
        "q3",
        lazy("bpb_tasks.q3.scorer:Q3Scorer"),
        "Q3 ball within one radius of truth (both null correct)",
        task="q3",
    )


@hookimpl
def bpb_diagnostics() -> Iterator[DiagnosticInfo]:
    diagnostics = {
        "q3_distance": ("Q3Distance", "Q3 position error (m): mean, median, p90, max"),
        "q3_distance_by_horizon": ("Q3DistanceByHorizon", "Q3 position error per horizon"),
        "q3_tolerance": ("Q3Tolerance", "Q3 accuracy if right within k radii"),
    }
    for name, (cls, summary) in diagnostics.items():
        yield DiagnosticInfo(name, lazy(f"bpb_tasks.q3.diagnostics:{cls}"), summary, tasks=("q3",))
