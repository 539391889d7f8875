"""Registration: cheap to import; the task, scorer and diagnostic load only when used."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core import DiagnosticInfo, ScorerInfo, TaskInfo, hookimpl, lazy


@hookimpl
def bpb_eval_tasks() -> Iterator[TaskInfo]:
    yield TaskInfo(
        "firsthit",
        lazy("bpb_firsthit.task:FirstHitTask"),
        "Which object ball the cue ball hits first, or none",
        family="billiards",
        title="First object ball hit",
    )


@hookimpl
def bpb_scorers() -> Iterator[ScorerInfo]:
    yield ScorerInfo(
        "firsthit",
        lazy("bpb_firsthit.scorer:FirstHitScorer"),
        "Right when the named ball (or none) is the first one hit",
        task="firsthit",
    )


@hookimpl
def bpb_diagnostics() -> Iterator[DiagnosticInfo]:
    yield DiagnosticInfo(
        "firsthit_outcomes",
        lazy("bpb_firsthit.diagnostics:FirstHitOutcomes"),
        "firsthit accuracy on scenes with and without a hit; hits answered 'none'",
        tasks=("firsthit",),
    )
