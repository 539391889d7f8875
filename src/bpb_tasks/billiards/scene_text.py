"""Reading ``init.json`` texts without building a pydantic model per scene (``bpb simulate``'s
fast path).

:func:`light_scene` accepts a text only when it is plainly valid: one pydantic-core call checks
it against plain typed dicts with the :class:`~bpb_tasks.billiards.scene.Scene` fields and no
others (same types and coercions, finite numbers, a positive horizon, non-negative integer ids;
no model instance is built); then ids must be distinct and include the cue ball (0), speeds at
most :data:`~bpb_tasks.billiards.scene.MAX_SPEED`, and every centre on the table, outside
every pocket circle and not overlapping another ball (:func:`light_scenes` checks this on
arrays, the tolerance as in :func:`~bpb_tasks.billiards.scene.check_geometry` or stricter).
Table, physics and pockets, when given, are validated by their pydantic models once per distinct
value. Any other text gives ``None``: the caller then reads it the ordinary way, which names the
file and field of whatever is wrong.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, Any, NamedTuple, NotRequired

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, ValidationError
from typing_extensions import TypedDict

from bpb_tasks.billiards.scene import MAX_SPEED, TOUCH_TOLERANCE, Physics, Pockets, Table

PARTS: dict[str, type[BaseModel]] = {"table": Table, "physics": Physics, "pockets": Pockets}
_STRICT = ConfigDict(extra="forbid", allow_inf_nan=False)


class _BallData(TypedDict):
    __pydantic_config__ = _STRICT  # type: ignore[misc]
    id: Annotated[int, Field(ge=0)]
    pos: tuple[float, float]
    vel: NotRequired[tuple[float, float]]


class _SceneData(TypedDict):
    __pydantic_config__ = _STRICT  # type: ignore[misc]
    scene_id: str
    horizon: Annotated[float, Field(gt=0)]
    table: NotRequired[dict[str, Any]]
    physics: NotRequired[dict[str, Any]]
    pockets: NotRequired[dict[str, Any]]
    balls: Annotated[list[_BallData], Field(min_length=1)]


_ADAPTER = TypeAdapter(_SceneData)
_SEEN: dict[str, list[tuple[object, BaseModel | None]]] = {}
_DEFAULTS: dict[str, BaseModel] = {name: model() for name, model in PARTS.items()}


class LightBall(NamedTuple):
    """A ball as the kernel needs it."""

    id: int
    pos: tuple[float, float]
    vel: tuple[float, float]


class LightScene(NamedTuple):
    """The fields of a :class:`~bpb_tasks.billiards.scene.Scene`, without its model."""

    scene_id: str
    horizon: float
    table: Any
    physics: Any
    pockets: Any
    balls: list[LightBall]


def light_scenes(texts: Sequence[bytes | str]) -> list[LightScene | None]:
    """The scenes of many ``init.json`` texts, ``None`` for each that is not plainly valid (the
    geometry is checked on arrays, all scenes of one table and ball count at once)."""
    scenes = [light_scene(t, geometry=False) for t in texts]
    groups: dict[tuple[int, ...], list[int]] = {}
    for i, s in enumerate(scenes):
        if s is not None:
            key = (len(s.balls), id(s.table), id(s.physics), id(s.pockets))
            groups.setdefault(key, []).append(i)
    for members in groups.values():
        ok = _geometry_many([scenes[i] for i in members])  # type: ignore[misc]
        for i, good in zip(members, ok, strict=True):
            if not good:
                scenes[i] = None
    return scenes


def light_scene(text: bytes | str, *, geometry: bool = True) -> LightScene | None:
    """The scene of an ``init.json`` text, or ``None`` when it is not plainly valid."""
    try:
        data = _ADAPTER.validate_json(text)
    except ValidationError:
        return None
    table, physics, pockets = (_part(name, data.get(name)) for name in PARTS)
    if table is None or physics is None or pockets is None:
        return None
    balls = [LightBall(b["id"], b["pos"], b.get("vel", (0.0, 0.0))) for b in data["balls"]]
    ids = {b.id for b in balls}
    if len(ids) != len(balls) or 0 not in ids:  # repeated ids or no cue ball
        return None
    if any(math.hypot(*b.vel) > MAX_SPEED for b in balls):
        return None
    scene = LightScene(data["scene_id"], data["horizon"], table, physics, pockets, balls)
    return scene if not geometry or _geometry_many([scene])[0] else None


def _part(name: str, value: object) -> BaseModel | None:
    if value is None:
        return _DEFAULTS[name]
    seen = _SEEN.setdefault(name, [])
    for known, model in seen:
        if known == value:
            return model
    try:
        found: BaseModel | None = PARTS[name].model_validate(value)
    except ValidationError:
        found = None
    if len(seen) < 64:
        seen.append((value, found))
    return found


def _geometry_many(scenes: Sequence[LightScene]) -> list[bool]:
    """On the table, outside the pocket circles, no overlap; for scenes sharing table, physics,
    pockets and ball count."""
    first = scenes[0]
    radius = first.physics.ball_radius
    pos = np.array([[b.pos for b in s.balls] for s in scenes], dtype=float)  # (k, n, 2)
    x, y = pos[..., 0], pos[..., 1]
    on_table = (x >= radius) & (x <= first.table.width - radius)
    on_table &= (y >= radius) & (y <= first.table.height - radius)
    good = on_table.all(axis=1)
    centres = np.array(first.pockets.centers, dtype=float).reshape(-1, 2)
    if len(centres):
        gaps = np.hypot(x[..., None] - centres[:, 0], y[..., None] - centres[:, 1])
        good &= (gaps > first.pockets.radius).all(axis=(1, 2))
    n = pos.shape[1]
    if n > 1:
        i, j = np.triu_indices(n, 1)
        apart = np.hypot(x[:, i] - x[:, j], y[:, i] - y[:, j])
        good &= (apart >= 2 * radius - TOUCH_TOLERANCE).all(axis=1)
    return [bool(g) for g in good]
