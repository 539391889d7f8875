"""Registers the built-in scorers ``q1``, ``q2`` and ``q3``."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.records import ScorerInfo, lazy


@hookimpl
def bpb_scorers() -> Iterator[ScorerInfo]:
    yield ScorerInfo(
        "q1", lazy("bpb_tasks.scoring.labels:Q1Scorer"), "Q1 per-ball accuracy", task="q1"
    )
    yield ScorerInfo(
        "q2", lazy("bpb_tasks.scoring.labels:Q2Scorer"), "Q2 exact wall-set match", task="q2"
    )
    yield ScorerInfo(
        "q3",
        lazy("bpb_tasks.scoring.positions:Q3Scorer"),
        "Q3 ball within one radius of truth (both null correct)",
        task="q3",
    )
