"""Registers task q2 with its scorer and diagnostic."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registry import DiagnosticInfo, ScorerInfo, TaskInfo, lazy


@hookimpl
def bpb_eval_tasks() -> Iterator[TaskInfo]:
    yield TaskInfo(
        "q2",
        lazy("bpb_tasks.q2.task:Q2Task"),
        "Q2: which walls the cue ball touches (T/F per wall)",
        family="billiards",
        default=True,
        title="Q2 wall contacts",
    )


@hookimpl
def bpb_scorers() -> Iterator[ScorerInfo]:
    yield ScorerInfo(
        "q2", lazy("bpb_tasks.q2.scorer:Q2Scorer"), "Q2 exact wall-set match", task="q2"
    )


@hookimpl
def bpb_diagnostics() -> Iterator[DiagnosticInfo]:
    yield DiagnosticInfo(
        "q2_confusion",
        lazy("bpb_tasks.q2.diagnostics:Q2Confusion"),
        "Q2 wall contacts, pooled and per wall: tp/fp/fn/tn, precision, recall, F1",
        tasks=("q2",),
    )
