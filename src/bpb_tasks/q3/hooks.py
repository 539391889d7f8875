"""Registers task q3."""

from __future__ import annotations

from collections.abc import Iterator

from bpb_core.hookspecs import hookimpl
from bpb_core.records import TaskInfo, lazy


@hookimpl
def bpb_tasks() -> Iterator[TaskInfo]:
    yield TaskInfo(
        "q3",
        lazy("bpb_tasks.q3.task:Q3Task"),
        "Q3: every ball's position at the horizon (null if pocketed)",
    )
