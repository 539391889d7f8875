"""The published answer formats of q1, q2 and q3: strict pydantic models and their JSON Schemas.

The parsers (:mod:`bpb_tasks.q1.task` ...) are lenient on purpose (``" t "`` reads as ``T``);
these models describe the canonical form a parsed answer is normalised to, which is what the
schemas in ``docs/schemas/`` publish and what ``--structured-output`` offers a provider.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

TF = Literal["T", "F"]
WallName = Literal["TOP", "BOTTOM", "LEFT", "RIGHT"]


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

    wall: WallName
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
