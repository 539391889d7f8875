"""Registers the paper's questions q1, q2 and q3 (each with its scorer and diagnostics), its
suite (the weighted total) and the stasis index over the three."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registry import (
    DiagnosticInfo,
    ReferenceInfo,
    ScorerInfo,
    SuiteInfo,
    TaskInfo,
    lazy,
)

PAPER_WEIGHTS = {"q1": 0.3, "q2": 0.3, "q3": 0.4}

# name: (task summary, task title, scorer summary), the task's and the scorer's module
QUESTIONS = {
    "q1": (
        "Q1: which object balls the cue ball touches (T/F per ball)",
        "Q1 ball collisions",
        "Q1 per-ball accuracy",
        ("questions.question", "questions.labels"),
    ),
    "q2": (
        "Q2: which walls the cue ball touches (T/F per wall)",
        "Q2 wall contacts",
        "Q2 exact wall-set match",
        ("questions.question", "questions.labels"),
    ),
    "q3": (
        "Q3: every ball's position at the horizon (null if pocketed)",
        "Q3 final positions",
        "Q3 ball within one radius of truth (both null correct)",
        ("q3.task", "q3.scorer"),
    ),
}

# name: (module:class, summary, tasks), in the order of the reports
DIAGNOSTICS = {
    "stasis": (
        "paper.stasis:StasisIndex",
        "Share of true contacts predicted absent and of moved balls predicted unmoved",
        ("q1", "q2", "q3"),
    ),
    "q1_confusion": (
        "questions.labels:Q1Confusion",
        "Q1 contacts: tp/fp/fn/tn, precision, recall, F1",
        ("q1",),
    ),
    "q2_confusion": (
        "questions.labels:Q2Confusion",
        "Q2 wall contacts, pooled and per wall: tp/fp/fn/tn, precision, recall, F1",
        ("q2",),
    ),
    "q3_distance": (
        "q3.scorer:Q3Distance",
        "Q3 position error (m): mean, median, p90, max",
        ("q3",),
    ),
    "q3_distance_by_horizon": (
        "q3.scorer:Q3DistanceByHorizon",
        "Q3 position error per horizon",
        ("q3",),
    ),
    "q3_tolerance": (
        "q3.scorer:Q3Tolerance",
        "Q3 accuracy if right within k radii",
        ("q3",),
    ),
}


@hookimpl
def bpb_eval_tasks() -> Iterator[TaskInfo]:
    for name, (summary, title, _, (where, _)) in QUESTIONS.items():
        task = lazy(f"bpb_tasks.{where}:{name.upper()}Task")
        yield TaskInfo(name, task, summary, family="billiards", default=True, title=title)


@hookimpl
def bpb_scorers() -> Iterator[ScorerInfo]:
    for name, (_, _, summary, (_, where)) in QUESTIONS.items():
        yield ScorerInfo(name, lazy(f"bpb_tasks.{where}:{name.upper()}Scorer"), summary, task=name)


@hookimpl
def bpb_diagnostics() -> Iterator[DiagnosticInfo]:
    for name, (where, summary, tasks) in DIAGNOSTICS.items():
        yield DiagnosticInfo(name, lazy(f"bpb_tasks.{where}"), summary, tasks=tasks)


@hookimpl
def bpb_suites() -> Iterator[SuiteInfo]:
    yield SuiteInfo(
        "total",
        summary="The paper's total score: 0.3 Q1 + 0.3 Q2 + 0.4 Q3",
        weights=PAPER_WEIGHTS,
        title="Total (0.3 Q1 + 0.3 Q2 + 0.4 Q3)",
    )


@hookimpl
def bpb_references() -> Iterator[ReferenceInfo]:
    from bpb_tasks.paper.figures import paper_reference

    yield paper_reference()
