"""Reading ``init.json`` texts without building a pydantic model per scene (``bpb simulate``'s
fast path).

:func:`light_scene` decodes a text with msgspec into plain structs with the
:class:`~bpb_tasks.billiards.scene.Scene` fields and no others (unknown fields refused, integer
ids >= 0, number pairs, a positive horizon, at least one ball). msgspec is as strict as the
model: it takes no strings for numbers, no floats for ids and no numbers out of float range, so
every text it accepts the model accepts with the same values. :func:`scene_groups` then checks,
on arrays and for many scenes at once: ids distinct and including the cue ball (0),
finite numbers, speeds below :data:`~bpb_tasks.billiards.scene.MAX_SPEED`, every centre on the
table, outside every pocket circle and not overlapping another ball, each with a margin on the
safe side of :func:`~bpb_tasks.billiards.scene.check_geometry`. Table, physics and pockets, when
given, are validated by their pydantic models once per distinct text. Any other text gives
``None``: the caller then reads it the ordinary way, which names the file and field of whatever
is wrong.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from itertools import chain
from typing import Annotated, Any, NamedTuple

import msgspec
import numpy as np
from pydantic import BaseModel, ValidationError
from pydantic_core import to_json

from bpb_tasks.billiards.scene import MAX_SPEED, TOUCH_TOLERANCE, Physics, Pockets, Table

PARTS: dict[str, type[BaseModel]] = {"table": Table, "physics": Physics, "pockets": Pockets}
_ABSENT = msgspec.Raw(b"")
_MAX_ID = 2**31 - 1  # ids travel through float arrays on the way to the kernel
_MARGIN = 1e-10  # metres or m/s on the safe side of the model's own checks


class LightBall(msgspec.Struct, forbid_unknown_fields=True, gc=False):
    """A ball as ``init.json`` holds it."""

    id: Annotated[int, msgspec.Meta(ge=0, le=_MAX_ID)]
    pos: tuple[float, float]
    vel: tuple[float, float] = (0.0, 0.0)


class _SceneText(msgspec.Struct, forbid_unknown_fields=True, gc=False):
    scene_id: str
    horizon: Annotated[float, msgspec.Meta(gt=0)]
    balls: Annotated[list[LightBall], msgspec.Meta(min_length=1)]
    table: msgspec.Raw = _ABSENT
    physics: msgspec.Raw = _ABSENT
    pockets: msgspec.Raw = _ABSENT


_DECODER = msgspec.json.Decoder(_SceneText)
_SEEN: dict[tuple[str, bytes], BaseModel | None] = {}
_LAST: dict[str, tuple[msgspec.Raw, BaseModel | None]] = {}
_DEFAULTS: dict[str, BaseModel] = {name: model() for name, model in PARTS.items()}


class LightScene(NamedTuple):
    """The fields of a :class:`~bpb_tasks.billiards.scene.Scene`, without its model."""

    scene_id: str
    horizon: float
    table: Any
    physics: Any
    pockets: Any
    balls: list[LightBall]


@dataclass
class SceneGroup:
    """Scenes sharing table, physics, pockets and ball count, as arrays sorted by ball id.

    Attributes:
        members: Positions of the scenes in the caller's sequence.
        horizons: ``(k,)`` the scenes' own horizons.
        names: The scenes' ids as JSON texts (quoted, escaped as pydantic-core writes them).
        parts: Their table, physics and pockets models.
        ids: ``(k, n)`` ball ids, ascending per scene.
        pos: ``(k, n, 2)`` centres in that order.
        vel: ``(k, n, 2)`` velocities in that order.
    """

    members: list[int]
    horizons: np.ndarray
    names: list[str]
    parts: tuple[Any, Any, Any]
    ids: np.ndarray
    pos: np.ndarray
    vel: np.ndarray


def light_scene(text: bytes | str, *, checks: bool = True) -> LightScene | None:
    """The scene of an ``init.json`` text, or ``None`` when it is not plainly valid (without
    ``checks``, only decoded: ids, numbers and geometry are left to :func:`scene_groups`)."""
    scene = decode_scenes([text])[0]
    if scene is None or not checks:
        return scene
    return scene if scene_groups([scene], checks=True) else None


def decode_scenes(texts: Sequence[bytes | str]) -> list[LightScene | None]:
    """:func:`light_scene` without checks for each of ``texts``."""
    scenes: list[LightScene | None] = [None] * len(texts)
    for parts, members, decoded in _decoded(texts).values():
        for i, data in zip(members, decoded, strict=True):
            table, physics, pockets = parts
            scenes[i] = LightScene(data.scene_id, data.horizon, table, physics, pockets, data.balls)
    return scenes


def decoded_groups(texts: Sequence[bytes | str]) -> list[SceneGroup]:
    """The plainly valid scenes of ``texts`` in groups (see :func:`scene_groups`), straight from
    the decoded structs; a text left out of every group is not plainly valid."""
    groups = (_arrays(members, found, parts) for parts, members, found in _decoded(texts).values())
    return [g for g in map(checked, groups) if g.members]


_Parts = tuple[Any, Any, Any]
_Decoded = dict[tuple[int, ...], tuple[_Parts, list[int], list[Any]]]


def _decoded(texts: Sequence[bytes | str]) -> _Decoded:
    """The texts that decode, by ball count and parts: ``(parts, positions, structs)``; the
    parts of the previous text are reused when the next one has the same texts for them."""
    keyed: _Decoded = {}
    decode = _DECODER.decode
    last: tuple[Any, ...] = ()
    parts: _Parts = (None, None, None)
    by_count: dict[int, tuple[_Parts, list[int], list[Any]]] = {}
    for i, text in enumerate(texts):
        try:
            data = decode(text)
        except (msgspec.MsgspecError, UnicodeDecodeError):  # not UTF-8: not a MsgspecError
            continue
        raws = (data.table, data.physics, data.pockets)
        if raws != last:
            last = raws
            parts = (part("table", raws[0]), part("physics", raws[1]), part("pockets", raws[2]))
            by_count = {} if None in parts else _bucket(keyed, parts)
        if parts[2] is None or parts[1] is None or parts[0] is None:
            continue
        n = len(data.balls)
        found = by_count.get(n)
        if found is None:
            found = keyed[(n, *map(id, parts))] = by_count[n] = (parts, [], [])
        found[1].append(i)
        found[2].append(data)
    return keyed


def _bucket(keyed: _Decoded, parts: _Parts) -> dict[int, tuple[_Parts, list[int], list[Any]]]:
    """The groups of ``keyed`` with these parts, by ball count."""
    ids = tuple(map(id, parts))
    return {key[0]: group for key, group in keyed.items() if key[1:] == ids}


def part(name: str, raw: msgspec.Raw) -> BaseModel | None:
    """The model of a table, physics or pockets text (``None``: not valid), validated once per
    distinct text."""
    if not len(raw):
        return _DEFAULTS[name]
    last = _LAST.get(name)
    if last is not None and last[0] == raw:  # the usual case: every scene has the same text
        return last[1]
    key = (name, bytes(raw))
    if key in _SEEN:
        found = _SEEN[key]
    else:
        try:
            found = PARTS[name].model_validate_json(key[1])
        except ValidationError:
            found = None
        if len(_SEEN) < 64:
            _SEEN[key] = found
    _LAST[name] = (raw, found)
    return found


def scene_groups(scenes: Sequence[Any], *, checks: bool) -> list[SceneGroup]:
    """The scenes (light scenes or scene models; ``None`` entries skipped) grouped by table,
    physics, pockets and ball count, as arrays sorted by ball id; with ``checks``, a scene that
    is not plainly valid (see the module's text) is left out of every group."""
    keyed: dict[tuple[Any, ...], list[int]] = {}
    for i, s in enumerate(scenes):
        if s is None:
            continue
        if isinstance(s, LightScene):  # parts are shared objects, one per distinct text
            key: tuple[Any, ...] = (len(s.balls), id(s.table), id(s.physics), id(s.pockets))
        else:
            pockets = (s.pockets.radius, tuple(map(tuple, s.pockets.centers)))
            key = (len(s.balls), s.table, s.physics, pockets)
        keyed.setdefault(key, []).append(i)
    groups = []
    for members in keyed.values():
        chosen = [scenes[i] for i in members]
        first = chosen[0]
        group = _arrays(members, chosen, (first.table, first.physics, first.pockets))
        if checks:
            group = checked(group)
        if group.members:
            groups.append(group)
    return groups


def checked(
    group: SceneGroup, plain: Callable[[SceneGroup], np.ndarray] | None = None
) -> SceneGroup:
    """``group`` without the scenes that are not plainly valid: per scene, ``plain(group)``
    (default :func:`plain_mask`; the scan path passes its compiled twin, which decides alike)."""
    ok = (plain or plain_mask)(group)
    if ok.all():
        return group
    keep = np.flatnonzero(ok).tolist()
    return SceneGroup(
        [group.members[i] for i in keep],
        group.horizons[keep],
        [group.names[i] for i in keep],
        group.parts,
        group.ids[keep],
        group.pos[keep],
        group.vel[keep],
    )


def _arrays(members: list[int], scenes: list[Any], parts: tuple[Any, Any, Any]) -> SceneGroup:
    k, n = len(scenes), len(scenes[0].balls)
    balls = [b for s in scenes for b in s.balls]
    ids = np.fromiter((b.id for b in balls), np.int64, k * n).reshape(k, n)
    flat = chain.from_iterable(b.pos + b.vel for b in balls)
    values = np.fromiter(flat, float, 4 * k * n).reshape(k, n, 4)
    horizons = np.fromiter((s.horizon for s in scenes), float, k)
    return by_id(members, horizons, [json_text(s.scene_id) for s in scenes], parts, ids, values)


def by_id(
    members: list[int],
    horizons: np.ndarray,
    names: list[str],
    parts: tuple[Any, Any, Any],
    ids: np.ndarray,
    values: np.ndarray,
) -> SceneGroup:
    """A group from ``(k, n)`` ids and ``(k, n, 4)`` ``x, y, vx, vy`` in any ball order, sorted by
    id within each scene."""
    if ids.shape[1] > 1 and not (np.diff(ids, axis=1) > 0).all():
        order = np.argsort(ids, axis=1, kind="stable")
        ids = np.take_along_axis(ids, order, axis=1)
        values = np.take_along_axis(values, order[..., None], axis=1)
    return SceneGroup(members, horizons, names, parts, ids, values[..., :2], values[..., 2:])


def json_text(value: str) -> str:
    """``value`` as pydantic-core writes it: quoted as it is when nothing in it needs escaping."""
    if value.isascii() and value.isprintable() and '"' not in value and "\\" not in value:
        return f'"{value}"'
    return to_json(value).decode()


def plain_limits(group: SceneGroup) -> PlainLimits:
    """The bounds :func:`plain_mask` compares with, worked out once per group."""
    table, physics, pockets = group.parts
    radius = physics.ball_radius
    fastest, reach = MAX_SPEED - _MARGIN, pockets.radius + _MARGIN
    least = 2 * radius - TOUCH_TOLERANCE + _MARGIN
    return PlainLimits(
        fastest * fastest,
        radius,
        table.width - radius,
        table.height - radius,
        reach * reach,
        least * least,
        np.array(pockets.centers, dtype=float).reshape(-1, 2),
    )


class PlainLimits(NamedTuple):
    """Squared speed limit, the table span a centre may take, squared pocket reach and squared
    least distance of two centres, and the pocket centres, as ``(p, 2)``."""

    speed2: float
    low: float
    x_high: float
    y_high: float
    reach2: float
    least2: float
    centres: np.ndarray


def plain_mask(group: SceneGroup) -> np.ndarray:
    """Per scene of ``group``: ids, numbers and geometry plainly valid (squared distances, with
    :data:`_MARGIN` far above their rounding error; bounds from :func:`plain_limits`).
    Coordinates are copied to contiguous ``(k, n)`` arrays first and pockets are taken one at a
    time: broadcasting strided views against every pocket at once cost four times as much."""
    lim = plain_limits(group)
    ids = group.ids
    n = ids.shape[1]
    x, y, vx, vy = (np.ascontiguousarray(a[..., c]) for a in (group.pos, group.vel) for c in (0, 1))
    good = ids[:, 0] == 0
    if n > 1:
        good &= (ids[:, 1:] > ids[:, :-1]).all(axis=1)  # sorted: distinct means increasing
    horizons = group.horizons
    good &= np.isfinite(horizons) & (horizons > 0)
    # No separate finiteness test of positions and velocities: a NaN fails every comparison
    # below and an infinity fails the speed or the table bounds.
    with np.errstate(invalid="ignore", over="ignore"):  # float products overflow to inf
        good &= (vx * vx + vy * vy < lim.speed2).all(axis=1)
        good &= ((x >= lim.low) & (x <= lim.x_high)).all(axis=1)
        good &= ((y >= lim.low) & (y <= lim.y_high)).all(axis=1)
        for cx, cy in lim.centres.tolist():
            dx, dy = x - cx, y - cy
            good &= (dx * dx + dy * dy > lim.reach2).all(axis=1)
        if n > 1:
            i, j = _pairs(n)
            dx, dy = x[:, i] - x[:, j], y[:, i] - y[:, j]
            good &= (dx * dx + dy * dy >= lim.least2).all(axis=1)
    return np.asarray(good, dtype=bool)


@functools.lru_cache(maxsize=64)
def _pairs(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The index pairs ``i < j`` of ``n`` balls."""
    return np.triu_indices(n, 1)
