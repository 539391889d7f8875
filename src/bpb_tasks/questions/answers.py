"""What the answer models of q1, q2 and q3 share: lenient field readers and validation helpers.

Tolerated variations: ``T``/``F`` in any case with surrounding whitespace, wall names in any case
with surrounding whitespace, ball ids as read by :func:`~bpb_tasks.questions.ids.ball_id`, and
extra keys inside items (ignored). Everything else is a :class:`~bpb_core.errors.ParseFailure`:
a missing or repeated id or wall, an answer other than T/F, a position that is not two finite
numbers inside the table.
"""

from __future__ import annotations

from typing import Any, Literal, TypeVar

from pydantic import BaseModel, ConfigDict, ValidationError

from bpb_core.errors import ParseFailure
from bpb_tasks.questions.ids import ball_id

TF = Literal["T", "F"]
M = TypeVar("M", bound=BaseModel)


class Item(BaseModel):
    """An entry of an answer list; extra keys are ignored."""

    model_config = ConfigDict(extra="ignore", frozen=True)


def read_id(value: Any) -> int:
    """A ball id for a ``mode="before"`` validator; ``ValueError`` when it is none."""
    found = ball_id(value)
    if found is None:
        raise ValueError("id must be an integer")
    return found


def upper(value: Any) -> Any:
    """Strings stripped and upper-cased (``" t "`` -> ``"T"``); anything else unchanged."""
    return value.strip().upper() if isinstance(value, str) else value


def load(model: type[M], task: str, value: Any) -> M:
    """Validate a decoded JSON value against ``model``; raise ParseFailure naming the field."""
    if not isinstance(value, dict):
        raise ParseFailure(f"{task}: the answer must be a JSON object")
    try:
        return model.model_validate(value)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise ParseFailure(f"{task}: {where}: {first['msg']}") from None


def check_ids(task: str, got: list[int], expected: list[int]) -> None:
    """Every expected id exactly once, and no other."""
    if len(got) != len(set(got)):
        raise ParseFailure(f"{task}: an id appears more than once")
    if sorted(got) != sorted(expected):
        missing = sorted(set(expected) - set(got))
        extra = sorted(set(got) - set(expected))
        raise ParseFailure(
            f"{task}: ids must be {sorted(expected)} (missing {missing}, extra {extra})"
        )
