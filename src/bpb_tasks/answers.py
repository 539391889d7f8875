"""Answer schemas of the built-in tasks (pydantic) and their validation against a scene.

Tolerated variations (documented in docs/tasks.md): ``T``/``F`` in any case with surrounding
whitespace, wall names in any case with surrounding whitespace, ball ids given as integer
strings (``"3"``), and extra keys inside items (ignored). Everything else is a
:class:`~bpb_core.errors.ParseFailure`: a missing or repeated id or wall, an answer other than
T/F, a position that is not two finite numbers inside the table.
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, ValidationError, field_validator

from bpb_core.errors import ParseFailure
from bpb_core.scene import WALLS, Scene, Wall

TF = Literal["T", "F"]


class _Item(BaseModel):
    model_config = ConfigDict(extra="ignore", frozen=True)


def _strict_id(value: Any) -> int:
    if isinstance(value, bool):
        raise ValueError("id must be an integer")
    if isinstance(value, str) and value.strip().lstrip("-").isdigit():
        return int(value.strip())
    if isinstance(value, int):
        return value
    raise ValueError("id must be an integer")


class BallAnswer(_Item):
    """Q1 item: did the cue ball touch ball ``id``."""

    id: int
    answer: TF

    @field_validator("id", mode="before")
    @classmethod
    def _id(cls, value: Any) -> int:
        return _strict_id(value)

    @field_validator("answer", mode="before")
    @classmethod
    def _tf(cls, value: Any) -> Any:
        return value.strip().upper() if isinstance(value, str) else value


class WallAnswer(_Item):
    """Q2 item: did the cue ball touch ``wall``."""

    wall: Wall
    answer: TF

    @field_validator("wall", "answer", mode="before")
    @classmethod
    def _upper(cls, value: Any) -> Any:
        return value.strip().upper() if isinstance(value, str) else value


class PositionAnswer(_Item):
    """Q3 item: centre of ball ``id`` at the horizon, ``None`` for pocketed."""

    id: int
    pos: tuple[float, float] | None

    @field_validator("id", mode="before")
    @classmethod
    def _id(cls, value: Any) -> int:
        return _strict_id(value)

    @field_validator("pos", mode="before")
    @classmethod
    def _numbers(cls, value: Any) -> Any:
        if value is None:
            return None
        if not isinstance(value, list | tuple) or len(value) != 2:
            raise ValueError("pos must be [x, y] or null")
        if any(isinstance(c, bool) or not isinstance(c, int | float) for c in value):
            raise ValueError("pos must hold two numbers")
        if not all(math.isfinite(c) for c in value):
            raise ValueError("pos must be finite")
        return value


class Q1Answer(BaseModel):
    """``{"answers": [{"id": 1, "answer": "T"}, ...]}``."""

    model_config = ConfigDict(extra="ignore", frozen=True)
    answers: list[BallAnswer]


class Q2Answer(BaseModel):
    """``{"answers": [{"wall": "TOP", "answer": "F"}, ...]}``."""

    model_config = ConfigDict(extra="ignore", frozen=True)
    answers: list[WallAnswer]


class Q3Answer(BaseModel):
    """``{"predictions": [{"id": 0, "pos": [x, y]}, ...]}``; ``pos`` null when pocketed."""

    model_config = ConfigDict(extra="ignore", frozen=True)
    predictions: list[PositionAnswer]


def _load(model: type[BaseModel], task: str, value: Any) -> Any:
    if not isinstance(value, dict):
        raise ParseFailure(f"{task}: the answer must be a JSON object")
    try:
        return model.model_validate(value)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise ParseFailure(f"{task}: {where}: {first['msg']}") from None


def _check_ids(task: str, got: list[int], expected: list[int]) -> None:
    if len(got) != len(set(got)):
        raise ParseFailure(f"{task}: an id appears more than once")
    if sorted(got) != sorted(expected):
        missing = sorted(set(expected) - set(got))
        extra = sorted(set(got) - set(expected))
        raise ParseFailure(
            f"{task}: ids must be {sorted(expected)} (missing {missing}, extra {extra})"
        )


def validate_q1(value: Any, scene: Scene) -> dict[str, Any]:
    """Validate a Q1 answer: one T/F per object ball, in id order."""
    answer: Q1Answer = _load(Q1Answer, "q1", value)
    object_ids = [b.id for b in scene.balls if b.id != 0]
    _check_ids("q1", [a.id for a in answer.answers], object_ids)
    items = sorted(answer.answers, key=lambda a: a.id)
    return {"answers": [{"id": a.id, "answer": a.answer} for a in items]}


def validate_q2(value: Any, scene: Scene) -> dict[str, Any]:
    """Validate a Q2 answer: one T/F per wall, in TOP, BOTTOM, LEFT, RIGHT order."""
    answer: Q2Answer = _load(Q2Answer, "q2", value)
    walls = [a.wall for a in answer.answers]
    if len(walls) != len(set(walls)) or set(walls) != set(WALLS):
        raise ParseFailure(f"q2: walls must be {list(WALLS)} once each, got {walls}")
    by_wall = {a.wall: a.answer for a in answer.answers}
    return {"answers": [{"wall": w, "answer": by_wall[w]} for w in WALLS]}


def validate_q3(value: Any, scene: Scene) -> dict[str, Any]:
    """Validate a Q3 answer: every ball once, at least one number, positions on the table."""
    answer: Q3Answer = _load(Q3Answer, "q3", value)
    _check_ids("q3", [p.id for p in answer.predictions], [b.id for b in scene.balls])
    if all(p.pos is None for p in answer.predictions):
        raise ParseFailure("q3: predictions: at least one position must be numeric")
    width, height = scene.table.width, scene.table.height
    for p in answer.predictions:
        if p.pos is not None and not (0 <= p.pos[0] <= width and 0 <= p.pos[1] <= height):
            raise ParseFailure(f"q3: predictions: ball {p.id} at {list(p.pos)} is off the table")
    items = sorted(answer.predictions, key=lambda p: p.id)
    return {
        "predictions": [{"id": p.id, "pos": None if p.pos is None else list(p.pos)} for p in items]
    }
