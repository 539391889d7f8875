"""Registers task q1 with its scorer and diagnostic."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registry import DiagnosticInfo, ScorerInfo, TaskInfo, lazy


@hookimpl
def bpb_eval_tasks() -> Iterator[TaskInfo]:
    yield TaskInfo(
        "q1",
        lazy("bpb_tasks.q1.task:Q1Task"),
        "Q1: which object balls the cue ball touches (T/F per ball)",
        family="billiards",
        default=True,
        title="Q1 ball collisions",
    )


@hookimpl
def bpb_scorers() -> Iterator[ScorerInfo]:
    yield ScorerInfo("q1", lazy("bpb_tasks.q1.scorer:Q1Scorer"), "Q1 per-ball accuracy", task="q1")


@hookimpl
def bpb_diagnostics() -> Iterator[DiagnosticInfo]:
    yield DiagnosticInfo(
        "q1_confusion",
        lazy("bpb_tasks.q1.diagnostics:Q1Confusion"),
        "Q1 contacts: tp/fp/fn/tn, precision, recall, F1",
        tasks=("q1",),
    )
