"""The answer each built-in task expects, cut from a ground-truth (or predicted) final state."""

from __future__ import annotations

from typing import Any

from bpb_core.errors import BadInput
from bpb_core.scene import FinalState


def answer_for_task(task: str, final: FinalState) -> dict[str, Any]:
    """The answer to ``task`` (q1, q2 or q3) in its answer format, taken from ``final``."""
    if task == "q1":
        return {"answers": [label.model_dump() for label in final.q1]}
    if task == "q2":
        return {"answers": [label.model_dump() for label in final.q2]}
    if task == "q3":
        return {
            "predictions": [
                {"id": p.id, "pos": None if p.pos is None else list(p.pos)}
                for p in final.predictions
            ]
        }
    raise BadInput(f"task {task!r}: no built-in answer format (known: q1, q2, q3)")
