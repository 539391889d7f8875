"""Deprecated shim: the expected answer now belongs to each task (``Task.expected``).

Kept so existing callers keep working; new code should use ``registry.task(name).expected(final)``.
"""

from __future__ import annotations

from typing import Any

from bpb_core.errors import BadInput
from bpb_core.scene import FinalState


def answer_for_task(task: str, final: FinalState) -> dict[str, Any]:
    """The answer to built-in ``task`` (q1, q2 or q3) in its answer format, taken from ``final``."""
    from bpb_tasks.q1.task import Q1Task
    from bpb_tasks.q2.task import Q2Task
    from bpb_tasks.q3.task import Q3Task

    tasks = {"q1": Q1Task, "q2": Q2Task, "q3": Q3Task}
    if task not in tasks:
        raise BadInput(f"task {task!r}: no built-in answer format (known: q1, q2, q3)")
    return tasks[task]().expected(final)
