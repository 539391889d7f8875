"""Registers task q1."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.records import TaskInfo, lazy


@hookimpl
def bpb_tasks() -> Iterator[TaskInfo]:
    yield TaskInfo(
        "q1",
        lazy("bpb_tasks.q1.task:Q1Task"),
        "Q1: which object balls the cue ball touches (T/F per ball)",
    )
