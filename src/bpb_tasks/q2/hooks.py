"""Registers task q2."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.records import TaskInfo, lazy


@hookimpl
def bpb_tasks() -> Iterator[TaskInfo]:
    yield TaskInfo(
        "q2",
        lazy("bpb_tasks.q2.task:Q2Task"),
        "Q2: which walls the cue ball touches (T/F per wall)",
    )
