"""bpb's tasks as Inspect AI tasks: ``bpb/q1``, ``bpb/q2``, ``bpb/q3`` and ``bpb/total`` (all
three, with the paper's weighted total as a metric).

Every task takes the same arguments (``-T name=value`` on Inspect's command line): ``data``
(a dataset folder or a Hugging Face export, default ``data``), ``input_mode`` (``image``,
``image+state``, ``state``), ``horizons`` (``1,3``), ``limit`` (scenes per horizon) and ``cot``.
"""

from __future__ import annotations

from typing import cast, get_args

from inspect_ai import Task, task

from bpb.inspect_build import bpb_task
from bpb_core.errors import BadInput
from bpb_core.interfaces import InputMode


@task
def q1(
    data: str = "data",
    input_mode: str = "image",
    horizons: str | None = None,
    limit: int | None = None,
    cot: bool | None = None,
) -> Task:
    """Which object balls the cue ball touches by the horizon (per-ball accuracy)."""
    return bpb_task(
        ["q1"], data, input_mode=_mode(input_mode), horizons=horizons, limit=limit, cot=cot
    )


@task
def q2(
    data: str = "data",
    input_mode: str = "image",
    horizons: str | None = None,
    limit: int | None = None,
    cot: bool | None = None,
) -> Task:
    """Which walls the cue ball touches by the horizon (exact wall-set match)."""
    return bpb_task(
        ["q2"], data, input_mode=_mode(input_mode), horizons=horizons, limit=limit, cot=cot
    )


@task
def q3(
    data: str = "data",
    input_mode: str = "image",
    horizons: str | None = None,
    limit: int | None = None,
    cot: bool | None = None,
) -> Task:
    """Every ball's position at the horizon (right within one ball radius)."""
    return bpb_task(
        ["q3"], data, input_mode=_mode(input_mode), horizons=horizons, limit=limit, cot=cot
    )


@task
def total(
    data: str = "data",
    input_mode: str = "image",
    horizons: str | None = None,
    limit: int | None = None,
    cot: bool | None = None,
) -> Task:
    """Q1-Q3 together, scored per task and by the paper's total (0.3 Q1 + 0.3 Q2 + 0.4 Q3)."""
    mode = _mode(input_mode)
    return bpb_task(
        None, data, suite="total", input_mode=mode, horizons=horizons, limit=limit, cot=cot
    )


def _mode(input_mode: str) -> InputMode:
    if input_mode not in get_args(InputMode):
        raise BadInput(f"input_mode: {input_mode!r}: use image, image+state or state")
    return cast("InputMode", input_mode)
