"""The answer formats of q1, q2 and q3: the lenient readers the parsers use, and the strict
published models they normalise to.

The one rule for reading a ball id or a wall name out of a model's answer (:func:`ball_id`,
:func:`wall_name`) serves both when a reply is validated (``parse``) and when a stored answer is
scored: an integer, an integer-valued float (``3.0``) or an integer string with optional sign and
surrounding spaces (``" 3"``, ``"-1"``) is an id; booleans and anything else are not. Wall names
are read in any case with surrounding spaces.

Tolerated variations: ``T``/``F`` in any case with surrounding whitespace, wall names in any case
with surrounding whitespace, ball ids as read by :func:`ball_id`, and extra keys inside items
(ignored). Everything else is a :class:`~bpb_core.errors.ParseFailure`: a missing or repeated id
or wall, an answer other than T/F, a position that is not two finite numbers inside the table.

The strict models (:class:`Q1Schema` ...) describe the canonical form a parsed answer is
normalised to, which is what the schemas in ``docs/schemas/`` publish and what
``--structured-output`` offers a provider.
"""

from __future__ import annotations

from typing import Annotated, Any, Generic, Literal, TypeVar

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError

from bpb_core.errors import ParseFailure
from bpb_tasks.billiards.scene.model import WALLS, Wall

TF = Literal["T", "F"]
M = TypeVar("M", bound=BaseModel)
ItemT = TypeVar("ItemT", bound="Item")


def ball_id(value: object) -> int | None:
    """The ball id ``value`` stands for, or ``None``."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        return int(value) if value.is_integer() else None
    if isinstance(value, str):
        text = value.strip()
        digits = text[1:] if text[:1] in "+-" else text
        return int(text) if digits.isdigit() and digits.isascii() else None
    return None


def wall_name(value: object) -> Wall | None:
    """The upper-case wall ``value`` names, or ``None``."""
    if isinstance(value, str):
        name = value.strip().upper()
        for wall in WALLS:
            if wall == name:
                return wall
    return None


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


BallId = Annotated[int, BeforeValidator(read_id)]
"""An item's ball id, read by :func:`ball_id`."""
Upper = BeforeValidator(upper)
"""Reads a string in any case with surrounding spaces (``TF``, ``Wall``)."""


class Answers(BaseModel, Generic[ItemT]):
    """``{"answers": [item, ...]}``: the reply of a label question (q1, q2)."""

    model_config = ConfigDict(extra="ignore", frozen=True)
    answers: list[ItemT]


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


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class BallLabel(_Strict):
    """Did the cue ball (ball 0) touch object ball ``id`` in [0, t]?"""

    id: int = Field(ge=1, description="Object ball id")
    answer: TF = Field(description="T: touched; F: not touched")


class Q1Schema(_Strict):
    """Q1 answer: one T/F per object ball (ids 1..6 in the paper's scenes)."""

    answers: list[BallLabel]


class WallLabel(_Strict):
    """Did the cue ball touch wall ``wall`` in [0, t]?"""

    wall: Wall
    answer: TF = Field(description="T: touched; F: not touched")


class Q2Schema(_Strict):
    """Q2 answer: one T/F per wall (TOP, BOTTOM, LEFT, RIGHT)."""

    answers: list[WallLabel]


class Position(_Strict):
    """Where ball ``id`` is at time t, or ``null`` when it was pocketed."""

    id: int = Field(ge=0, description="Ball id (0 is the cue ball)")
    pos: list[float] | None = Field(
        min_length=2, max_length=2, description="[x, y] in metres, or null when pocketed"
    )


class Q3Schema(_Strict):
    """Q3 answer: every ball's position at time t (ids 0..6 in the paper's scenes)."""

    predictions: list[Position]


def schema_of(model: type[BaseModel], task: str) -> dict[str, Any]:
    """The JSON Schema of ``model`` with the task's name as its title."""
    schema = model.model_json_schema()
    schema["title"] = f"{task} answer"
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    return schema
