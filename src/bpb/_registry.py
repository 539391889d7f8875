"""bpb's tasks as Inspect AI tasks, registered by importing this module (Inspect's entry point:
group ``inspect_ai``, name ``bpb``): ``bpb/q1``, ``bpb/q2``, ``bpb/q3`` and ``bpb/total`` (all
three, with the paper's weighted total as a metric).

Every task takes the same arguments (``-T name=value`` on Inspect's command line): ``data``
(a dataset folder or a Hugging Face export, default ``data``), ``input_mode`` (``image``,
``image+state``, ``state``), ``horizons`` (``1,3``), ``limit`` (scenes per horizon) and ``cot``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import cast, get_args

from inspect_ai import Task, task

from bpb.inspect_build import bpb_task
from bpb_core.errors import BadInput
from bpb_core.interfaces import InputMode

__all__ = ["q1", "q2", "q3", "total"]


def _inspect_task(
    name: str, tasks: list[str] | None, suite: str | None, summary: str
) -> Callable[..., Task]:
    """The Inspect task ``bpb/<name>``: ``tasks``, or the ``suite``'s tasks."""

    def build(
        data: str = "data",
        input_mode: str = "image",
        horizons: str | None = None,
        limit: int | None = None,
        cot: bool | None = None,
    ) -> Task:
        if input_mode not in get_args(InputMode):
            raise BadInput(f"input_mode: {input_mode!r}: use image, image+state or state")
        mode = cast("InputMode", input_mode)
        return bpb_task(
            tasks, data, suite=suite, input_mode=mode, horizons=horizons, limit=limit, cot=cot
        )

    build.__doc__ = summary
    return task(name=name)(build)


q1 = _inspect_task(
    "q1",
    ["q1"],
    None,
    "Which object balls the cue ball touches by the horizon (per-ball accuracy).",
)
q2 = _inspect_task(
    "q2", ["q2"], None, "Which walls the cue ball touches by the horizon (exact wall-set match)."
)
q3 = _inspect_task(
    "q3", ["q3"], None, "Every ball's position at the horizon (right within one ball radius)."
)
total = _inspect_task(
    "total",
    None,
    "total",
    "Q1-Q3 together, scored per task and by the paper's total (0.3 Q1 + 0.3 Q2 + 0.4 Q3).",
)
