"""The billiards scene: the model of ``init.json`` (SPEC section 4).

This pydantic model is half of the data contract of a billiards dataset (the other half,
``final.json``, is :mod:`bpb_tasks.billiards.truth.final`); :func:`scene_json_schema` publishes it
as a JSON Schema.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, Strict, field_validator, model_validator

Wall = Literal["TOP", "BOTTOM", "LEFT", "RIGHT"]
WALLS: tuple[Wall, ...] = ("TOP", "BOTTOM", "LEFT", "RIGHT")
TOUCH_TOLERANCE = 1e-9  # balls may touch within this many metres; deeper overlap is bad input
MAX_SPEED = 100.0  # m/s; a hard break shot is about 15. Far beyond, v^2 overflows and the
# event count of a horizon explodes, so such a scene is refused rather than simulated.

DEFAULT_RADIUS = 0.028575
DEFAULT_POCKETS: list[tuple[float, float]] = [
    (0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (0.0, 1.0), (1.0, 1.0), (2.0, 1.0),
]  # fmt: skip


class StrictModel(BaseModel):
    """Unknown fields refused, and no coercion: ``true`` is no count, ``"0"`` no id and ``1`` no
    name (a float field still takes an integer, ``2`` for ``2.0``)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False, strict=True)


Vec = Annotated[tuple[float, float], Strict(False)]  # a JSON or TOML array; its numbers strict


class Table(StrictModel):
    """Table size in metres; origin bottom-left, x right, y up."""

    width: float = Field(2.0, gt=0)
    height: float = Field(1.0, gt=0)


class Physics(StrictModel):
    """Physical constants; every one is recorded with the scene."""

    ball_radius: float = Field(DEFAULT_RADIUS, gt=0)
    mu: float = Field(0.002, ge=0)
    g: float = Field(9.8, gt=0)
    wall_restitution: float = Field(1.0, ge=0, le=1)

    @model_validator(mode="after")
    def _finite_friction(self) -> Physics:
        # Each value alone is finite, but mu*g may overflow: the simulators would then move
        # balls by inf - inf (NaN) or stop them at once.
        if not math.isfinite(self.mu * self.g):
            raise ValueError(
                f"mu*g = {self.mu:g} * {self.g:g} overflows (not a finite deceleration in "
                "m/s^2); make mu or g smaller"
            )
        return self


class Pockets(StrictModel):
    """Pocket circles; a ball is pocketed when its centre first comes within ``radius``."""

    radius: float = Field(0.06, ge=0)
    centers: list[Vec] = Field(default_factory=lambda: list(DEFAULT_POCKETS))


class Ball(StrictModel):
    """A ball's id, centre position (m) and velocity (m/s) at t = 0."""

    id: int = Field(ge=0)
    pos: Vec
    vel: Vec = (0.0, 0.0)

    @field_validator("vel")
    @classmethod
    def _speed(cls, value: Vec) -> Vec:
        if math.hypot(*value) > MAX_SPEED:
            raise ValueError(f"speed {math.hypot(*value):g} m/s is above {MAX_SPEED:g} m/s")
        return value


class Scene(StrictModel):
    """An initial state: the content of ``init.json``."""

    scene_id: str
    horizon: float = Field(gt=0)
    table: Table = Field(default_factory=Table)
    physics: Physics = Field(default_factory=Physics)
    pockets: Pockets = Field(default_factory=Pockets)
    balls: list[Ball] = Field(min_length=1)

    def ball(self, ball_id: int) -> Ball:
        """The ball with id ``ball_id``."""
        for ball in self.balls:
            if ball.id == ball_id:
                return ball
        raise KeyError(ball_id)

    @model_validator(mode="after")
    def _geometry(self) -> Scene:
        """Raise ValueError naming the ball when there is no cue ball (id 0), ids repeat, a
        centre is off the table or within a pocket circle (tangency included: such a ball would
        be pocketed at t = 0), or balls overlap by more than :data:`TOUCH_TOLERANCE`."""
        radius, balls = self.physics.ball_radius, self.balls
        if all(ball.id != 0 for ball in balls):
            raise ValueError("balls: no cue ball (a ball with id 0)")
        x_lo, x_hi, y_lo, y_hi = table_box(self.table, radius)
        lo_x, hi_x = x_lo - TOUCH_TOLERANCE, x_hi + TOUCH_TOLERANCE
        lo_y, hi_y = y_lo - TOUCH_TOLERANCE, y_hi + TOUCH_TOLERANCE
        centers, pocket_radius = self.pockets.centers, self.pockets.radius
        seen: set[int] = set()
        for i, ball in enumerate(balls):
            if ball.id in seen:
                raise ValueError(f"balls[{i}].id: duplicate ball id {ball.id}")
            seen.add(ball.id)
            x, y = pos = ball.pos
            if not (lo_x <= x <= hi_x and lo_y <= y <= hi_y):
                raise ValueError(f"balls[{i}].pos: ball {ball.id} at {list(pos)} is off the table")
            for k, centre in enumerate(centers):
                if math.dist(pos, centre) <= pocket_radius:
                    raise ValueError(
                        f"balls[{i}].pos: ball {ball.id} at {list(pos)} starts inside pocket {k}"
                    )
        min_gap = 2 * radius - TOUCH_TOLERANCE
        places = [ball.pos for ball in balls]
        for i, a in enumerate(places):
            for j in range(i + 1, len(places)):
                if math.dist(a, places[j]) < min_gap:
                    raise ValueError(f"balls: ball {balls[i].id} and ball {balls[j].id} overlap")
        return self


def table_box(table: Table, radius: float) -> tuple[float, float, float, float]:
    """``(x_lo, x_hi, y_lo, y_hi)``: where the centre of a ball of ``radius`` lies on ``table``,
    ``radius`` from every cushion (a scene's balls may touch within :data:`TOUCH_TOLERANCE`)."""
    return radius, table.width - radius, radius, table.height - radius


def scene_json_schema() -> dict[str, Any]:
    """JSON Schema of ``init.json``."""
    return Scene.model_json_schema()
