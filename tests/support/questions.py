"""The three billiards questions as task objects (built directly: no registry at import time)."""

from __future__ import annotations

from bpb_tasks.q3.task import Q3Task
from bpb_tasks.questions.question import BilliardsQuestion, Q1Task, Q2Task


def questions() -> dict[str, BilliardsQuestion]:
    """Fresh ``q1``, ``q2`` and ``q3`` task objects."""
    return {"q1": Q1Task(), "q2": Q2Task(), "q3": Q3Task()}
