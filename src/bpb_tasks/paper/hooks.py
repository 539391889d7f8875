"""Registers the paper's suite (the weighted total) and the stasis index over Q1-Q3."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.registry import DiagnosticInfo, SuiteInfo, lazy

PAPER_WEIGHTS = {"q1": 0.3, "q2": 0.3, "q3": 0.4}


@hookimpl
def bpb_suites() -> Iterator[SuiteInfo]:
    yield SuiteInfo(
        "total",
        summary="The paper's total score: 0.3 Q1 + 0.3 Q2 + 0.4 Q3",
        weights=PAPER_WEIGHTS,
        title="Total (0.3 Q1 + 0.3 Q2 + 0.4 Q3)",
    )


@hookimpl
def bpb_diagnostics() -> Iterator[DiagnosticInfo]:
    yield DiagnosticInfo(
        "stasis",
        lazy("bpb_tasks.paper.stasis:StasisIndex"),
        "Share of true contacts predicted absent and of moved balls predicted unmoved",
        tasks=("q1", "q2", "q3"),
    )
