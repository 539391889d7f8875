"""Reading a chunk of ``init.json`` texts with compiled code (``bpb simulate``'s fast path).

:func:`text_groups` hands every text to :func:`_scan` (numba), which takes only the layout the
:class:`~bpb_tasks.billiards.scene.Scene` model writes: the keys ``scene_id``, ``horizon``,
``table``, ``physics``, ``pockets`` and ``balls`` in that order, each ball as ``id``, ``pos`` and
``vel``, JSON whitespace allowed between tokens. It checks the grammar of every number, takes ids
of up to ten digits without a sign or leading zero, and takes scene ids only of printable ASCII
with no quote or backslash, so each id's JSON text is its bytes. It does not convert numbers: it
copies their texts into one JSON list, which msgspec turns into floats in one call, so every value
is the one msgspec gives when it decodes the texts one by one
(:func:`~bpb_tasks.billiards.scene_text.decode_scenes`). Table, physics and pockets are taken as
their raw texts, validated once by their models, and a scene whose raw texts differ from the
chunk's first taken scene is left out.

Texts the scan does not take go to :func:`~bpb_tasks.billiards.scene_text.decoded_groups`
(msgspec, one struct per scene), and the same checks on arrays then apply to both. Decoding
structs and filling arrays from them was a quarter of ``bpb simulate``'s time per scene.
"""

from __future__ import annotations

from collections.abc import Sequence

import msgspec
import numpy as np

from bpb_tasks.billiards.scene_text import (
    PARTS,
    SceneGroup,
    by_id,
    checked,
    decoded_groups,
    part,
    plain_limits,
)
from bpb_tasks.billiards.truth_bytes import put
from bpb_tasks.simulators.analytic.kernel_roots import jit

_KEYS = [b'"scene_id"', b'"horizon"', b'"table"', b'"physics"', b'"pockets"', b'"balls"']
_KEYS += [b'"id"', b'"pos"', b'"vel"']
SCENE_ID, HORIZON, TABLE, PHYSICS, POCKETS, BALLS, ID, POS, VEL = range(9)
_TABLE = np.frombuffer(b"".join(_KEYS), dtype=np.uint8)
_OFFSETS = np.cumsum([0, *map(len, _KEYS)]).astype(np.int64)
_FLOATS = msgspec.json.Decoder(list[float])
_MAX_ID = 2**31 - 1

TAKEN, NOT_PLAIN, OTHER_PARTS = 0, 1, 2  # what _scan made of each text


def text_groups(texts: Sequence[bytes]) -> list[SceneGroup]:
    """The plainly valid scenes of ``texts`` in groups of one table, physics, pockets and ball
    count (see :class:`~bpb_tasks.billiards.scene_text.SceneGroup`); a text left out of every
    group is not plainly valid and goes the ordinary way."""
    groups, rest = scanned_groups(texts)
    if rest:
        for group in decoded_groups([texts[i] for i in rest]):
            group.members = [rest[i] for i in group.members]
            groups.append(group)
    return groups


def scanned_groups(texts: Sequence[bytes]) -> tuple[list[SceneGroup], list[int]]:
    """The groups of the texts :func:`_scan` takes, and the positions of the others."""
    joined = b"".join(texts)
    bounds = np.zeros(len(texts) + 1, dtype=np.int64)
    np.cumsum(np.fromiter(map(len, texts), np.int64, len(texts)), out=bounds[1:])
    text = np.frombuffer(joined, dtype=np.uint8)
    status, counts, first_number, first_ball, spans, numbers, ids, names = _scanned(text, bounds)
    taken = status == TAKEN
    groups: list[SceneGroup] = []
    if taken.any():
        at = int(np.argmax(taken))
        table, physics, pockets = (
            part(name, msgspec.Raw(joined[spans[at, 2 * c] : spans[at, 2 * c + 1]]))
            for c, name in enumerate(PARTS)
        )
        found = (table, physics, pockets)
        values = _values(numbers) if None not in found else None
        if values is None:
            taken[:] = False
        else:
            for n in np.unique(counts[taken]).tolist():
                members = np.flatnonzero(taken & (counts == n))
                flat = first_number[members, None] + np.arange(1, 4 * n + 1)
                group = by_id(
                    members.tolist(),
                    values[first_number[members]],
                    [names[i] for i in members.tolist()],
                    found,
                    ids[first_ball[members, None] + np.arange(n)],
                    values[flat].reshape(len(members), n, 4),
                )
                group = checked(group, compiled_plain)
                if group.members:
                    groups.append(group)
    return groups, np.flatnonzero(~taken).tolist()


def _scanned(
    text: np.ndarray, bounds: np.ndarray
) -> tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, bytes, np.ndarray, list[str]
]:
    """:func:`_scan`'s results: per text its status, ball count, index of its horizon among the
    numbers and of its first ball among the ids, and its parts' ``(start, stop)`` in ``text``;
    then the numbers' JSON list, the ids, and each text's scene id as JSON (empty if not
    taken)."""
    k = len(bounds) - 1
    status = np.empty(k, dtype=np.int8)
    counts = np.zeros(k, dtype=np.int64)
    first_number = np.zeros(k, dtype=np.int64)
    first_ball = np.zeros(k, dtype=np.int64)
    spans = np.zeros((k, 6), dtype=np.int64)
    numbers = np.empty(len(text) + 2, dtype=np.uint8)
    ids = np.empty(len(text) // 16 + 1, dtype=np.int64)  # a ball takes more than 16 bytes
    names = np.empty(len(text) + k, dtype=np.uint8)
    used, named = _scan(
        text, bounds, _TABLE, _OFFSETS, status, counts, first_number, first_ball, spans,
        numbers, ids, names,
    )  # fmt: skip
    found = names[:named].tobytes().decode("ascii").split("\n")
    return status, counts, first_number, first_ball, spans, numbers[:used].tobytes(), ids, found


def _values(numbers: bytes) -> np.ndarray | None:
    """The floats of the numbers' JSON list (msgspec's values), or ``None`` when one is out of
    float range or not a JSON number: then the whole chunk goes the struct way, which finds which
    text holds it."""
    try:
        found = _FLOATS.decode(numbers)
        return np.fromiter(found, float, len(found))
    except msgspec.DecodeError:
        return None


def compiled_plain(group: SceneGroup) -> np.ndarray:
    """:func:`~bpb_tasks.billiards.scene_text.plain_mask` in one compiled pass: the same
    comparisons, in the same direction (a NaN fails each), on the same bounds. The numpy form
    took about 1.2 of ``bpb simulate``'s 20 µs per scene (profiled) in thirty whole-array
    steps; reading a chunk's texts into groups now takes about 0.5 µs less per scene."""
    lim = plain_limits(group)
    return _plain_rows(
        np.ascontiguousarray(group.ids, dtype=np.int64),
        np.ascontiguousarray(group.pos, dtype=float),
        np.ascontiguousarray(group.vel, dtype=float),
        np.ascontiguousarray(group.horizons, dtype=float),
        np.array([lim.speed2, lim.low, lim.x_high, lim.y_high, lim.reach2, lim.least2]),
        np.ascontiguousarray(lim.centres, dtype=float),
    )


@jit
def _plain_rows(
    ids: np.ndarray,
    pos: np.ndarray,
    vel: np.ndarray,
    horizons: np.ndarray,
    limits: np.ndarray,
    centres: np.ndarray,
) -> np.ndarray:
    """Per scene: :func:`_plain_row`."""
    good = np.zeros(ids.shape[0], dtype=np.bool_)
    for s in range(ids.shape[0]):
        good[s] = _plain_row(ids[s], pos[s], vel[s], horizons[s], limits, centres)
    return good


@jit
def _plain_row(
    ids: np.ndarray,
    pos: np.ndarray,
    vel: np.ndarray,
    horizon: float,
    limits: np.ndarray,
    centres: np.ndarray,
) -> bool:
    """One scene's ids ascending from 0, a finite positive horizon, and every ball under the
    speed limit, inside the table span, outside each pocket's reach and apart from the others
    (``limits``: :class:`~bpb_tasks.billiards.scene_text.PlainLimits`' first six fields)."""
    speed2, low, x_high, y_high, reach2, least2 = (
        limits[0], limits[1], limits[2], limits[3], limits[4], limits[5],
    )  # fmt: skip
    n = ids.shape[0]
    if ids[0] != 0:
        return False
    for b in range(1, n):
        if not ids[b] > ids[b - 1]:
            return False
    if not (np.isfinite(horizon) and horizon > 0):
        return False
    for b in range(n):
        x, y, vx, vy = pos[b, 0], pos[b, 1], vel[b, 0], vel[b, 1]
        if not vx * vx + vy * vy < speed2:
            return False
        if not (x >= low and x <= x_high and y >= low and y <= y_high):
            return False
        for c in range(centres.shape[0]):
            dx, dy = x - centres[c, 0], y - centres[c, 1]
            if not dx * dx + dy * dy > reach2:
                return False
    for i in range(n):
        for j in range(i + 1, n):
            dx, dy = pos[i, 0] - pos[j, 0], pos[i, 1] - pos[j, 1]
            if not dx * dx + dy * dy >= least2:
                return False
    return True


@jit
def _b(t: np.ndarray, p: int) -> int:
    """``t[p]`` for ``p >= 0``: an unsigned index spares numba its test for a negative one
    on every byte (three times faster)."""
    return t[np.uint64(p)]  # type: ignore[no-any-return]


@jit
def _space(t: np.ndarray, p: int, end: int) -> int:
    """The first position from ``p`` that is not JSON whitespace."""
    while p < end and (_b(t, p) == 32 or _b(t, p) == 10 or _b(t, p) == 13 or _b(t, p) == 9):
        p += 1
    return p


@jit
def _char(t: np.ndarray, p: int, end: int, c: int) -> int:
    """After whitespace, the byte ``c``: the position after it, else -1."""
    p = _space(t, p, end)
    if p < end and _b(t, p) == c:
        return p + 1
    return -1


@jit
def _key(t: np.ndarray, p: int, end: int, keys: np.ndarray, offsets: np.ndarray, which: int) -> int:
    """After whitespace, the key ``which`` of :data:`_KEYS` and its colon: the position after
    them, else -1."""
    p = _space(t, p, end)
    a, b = offsets[which], offsets[which + 1]
    if p + (b - a) > end:
        return -1
    for i in range(b - a):
        if _b(t, p + i) != _b(keys, a + i):
            return -1
    return _char(t, p + (b - a), end, 58)


@jit
def _digits(t: np.ndarray, p: int, end: int) -> int:
    while p < end and 48 <= _b(t, p) <= 57:
        p += 1
    return p


@jit
def _put_number(t: np.ndarray, p: int, end: int, out: np.ndarray, at: int) -> tuple[int, int]:
    """After whitespace, the bytes a JSON number is made of (digits, ``.``, ``e``, ``E``, ``+``,
    ``-``), copied to ``out[at:]`` with a comma after them: ``(after them, new at)``, or ``p``
    -1 when there are none. msgspec checks their grammar when it reads the list."""
    p = _space(t, p, end)
    start = p
    to = np.uint64(at)
    while p < end:
        c = _b(t, p)
        if not (48 <= c <= 57 or c == 46 or c == 45 or c == 101 or c == 69 or c == 43):
            break
        out[to] = c
        to += np.uint64(1)
        p += 1
    if p == start:
        return -1, at
    out[to] = 44
    return p, np.int64(to) + 1  # type: ignore[return-value]  # an int in compiled code


@jit
def _pair(t: np.ndarray, p: int, end: int, out: np.ndarray, at: int) -> tuple[int, int]:
    """``[number, number]`` copied as two numbers: ``(after it, new at)``, ``p`` -1 if not."""
    for c in (91, 44):  # "[" before the first number, "," before the second
        p = _char(t, p, end, c) if p >= 0 else -1
        if p < 0:
            return -1, at
        p, at = _put_number(t, p, end, out, at)
    return (_char(t, p, end, 93) if p >= 0 else -1), at


@jit
def _object(t: np.ndarray, p: int, end: int) -> tuple[int, int]:
    """After whitespace, a ``{...}`` value (brackets matched, strings skipped): its
    ``(start, stop)``, else ``(-1, -1)``. Its model validates it; this only finds its end."""
    p = _space(t, p, end)
    if p >= end or _b(t, p) != 123:
        return -1, -1
    start = p
    depth = 0
    while p < end:
        c = _b(t, p)
        if c == 34:
            p += 1
            while p < end and _b(t, p) != 34:
                p += 2 if _b(t, p) == 92 else 1
            if p >= end:
                return -1, -1
        elif c == 123 or c == 91:
            depth += 1
        elif c == 125 or c == 93:
            depth -= 1
            if depth == 0:
                return start, p + 1
        p += 1
    return -1, -1


@jit
def _ball_id(t: np.ndarray, p: int, end: int) -> tuple[int, int]:
    """After whitespace, an id: digits, no leading zero, at most :data:`_MAX_ID`; ``(after
    it, value)`` or ``(-1, 0)``."""
    p = _space(t, p, end)
    stop = _digits(t, p, end)
    if stop == p or stop - p > 10 or (_b(t, p) == 48 and stop - p > 1):
        return -1, 0
    value = 0
    for q in range(p, stop):
        value = value * 10 + (_b(t, q) - 48)
    if value > _MAX_ID:
        return -1, 0
    return stop, value


@jit
def _parts(t: np.ndarray, p: int, end: int, keys: np.ndarray, offsets: np.ndarray,
           span: np.ndarray, ref: np.ndarray) -> tuple[int, int]:  # fmt: skip
    """``,"table":{...},"physics":{...},"pockets":{...}`` from ``p``, their spans put in
    ``span``: ``(after them, status)``. Once a first text is taken (``ref[0] >= 0``, its spans)
    each part must be its bytes, compared instead of scanned."""
    for c in range(3):
        p = _char(t, p, end, 44) if p >= 0 else -1
        p = _key(t, p, end, keys, offsets, TABLE + c) if p >= 0 else -1
        if p < 0:
            return -1, NOT_PLAIN
        p = _space(t, p, end)
        span[2 * c] = p
        if ref[0] < 0:
            start, p = _object(t, p, end)
            if start < 0:
                return -1, NOT_PLAIN
        else:
            size = ref[2 * c + 1] - ref[2 * c]
            if p + size > end:
                return -1, OTHER_PARTS
            for i in range(size):
                if _b(t, p + i) != _b(t, ref[2 * c] + i):
                    return -1, OTHER_PARTS
            p += size
        span[2 * c + 1] = p
    return p, TAKEN


@jit
def _scene(
    t: np.ndarray,
    p: int,
    end: int,
    keys: np.ndarray,
    offsets: np.ndarray,
    span: np.ndarray,
    ref: np.ndarray,
    numbers: np.ndarray,
    at: int,
    ids: np.ndarray,
    ball: int,
    names: np.ndarray,
    named: int,
) -> tuple[int, int, int, int]:
    """One text from ``p`` to ``end``: its status (:data:`TAKEN` when it has the layout), and
    the cursors of ``numbers``, ``ids`` and ``names`` after what it wrote to them."""
    fail = (NOT_PLAIN, at, ball, named)
    p = _char(t, p, end, 123)
    p = _key(t, p, end, keys, offsets, SCENE_ID) if p >= 0 else -1
    p = _char(t, p, end, 34) if p >= 0 else -1
    if p < 0:
        return fail
    start = p
    while p < end and 32 <= _b(t, p) <= 126 and _b(t, p) != 34 and _b(t, p) != 92:
        p += 1
    if p >= end or _b(t, p) != 34:
        return fail
    named = put(names, named, t, start - 1, p + 1)
    p = _char(t, p + 1, end, 44)
    p = _key(t, p, end, keys, offsets, HORIZON) if p >= 0 else -1
    if p < 0:
        return fail
    p, at = _put_number(t, p, end, numbers, at)
    p, status = _parts(t, p, end, keys, offsets, span, ref) if p >= 0 else (-1, NOT_PLAIN)
    if p < 0:
        return status, fail[1], fail[2], fail[3]
    p = _char(t, p, end, 44)
    p = _key(t, p, end, keys, offsets, BALLS) if p >= 0 else -1
    p = _char(t, p, end, 91) if p >= 0 else -1
    if p < 0:
        return fail
    while True:
        p = _char(t, p, end, 123)
        p = _key(t, p, end, keys, offsets, ID) if p >= 0 else -1
        if p < 0:
            return fail
        p, value = _ball_id(t, p, end)
        p = _char(t, p, end, 44) if p >= 0 else -1
        p = _key(t, p, end, keys, offsets, POS) if p >= 0 else -1
        if p < 0:
            return fail
        ids[ball] = value
        ball += 1
        p, at = _pair(t, p, end, numbers, at)
        p = _char(t, p, end, 44) if p >= 0 else -1
        p = _key(t, p, end, keys, offsets, VEL) if p >= 0 else -1
        if p < 0:
            return fail
        p, at = _pair(t, p, end, numbers, at)
        p = _char(t, p, end, 125) if p >= 0 else -1
        if p < 0:
            return fail
        p = _space(t, p, end)
        if p < end and _b(t, p) == 44:
            p += 1
            continue
        break
    p = _char(t, p, end, 93)
    p = _char(t, p, end, 125) if p >= 0 else -1
    if p < 0 or _space(t, p, end) != end:
        return fail
    return TAKEN, at, ball, named


@jit
def _scan(
    t: np.ndarray,
    bounds: np.ndarray,
    keys: np.ndarray,
    offsets: np.ndarray,
    status: np.ndarray,
    counts: np.ndarray,
    first_number: np.ndarray,
    first_ball: np.ndarray,
    spans: np.ndarray,
    numbers: np.ndarray,
    ids: np.ndarray,
    names: np.ndarray,
) -> tuple[int, int]:
    """Scan the texts ``t[bounds[j]:bounds[j + 1]]``; returns the bytes used of ``numbers``
    (the JSON list) and of ``names``."""
    at, ball, named, count = 1, 0, 0, 0
    numbers[0] = 91  # "["
    ref = np.full(6, -1, dtype=np.int64)
    for j in range(len(bounds) - 1):
        found, at2, ball2, named2 = _scene(
            t, bounds[j], bounds[j + 1], keys, offsets, spans[j], ref, numbers, at, ids, ball,
            names, named,
        )  # fmt: skip
        status[j] = found
        if found == TAKEN:
            if ref[0] < 0:
                ref[:] = spans[j]
            counts[j] = ball2 - ball
            first_number[j] = count
            first_ball[j] = ball
            count += 1 + 4 * (ball2 - ball)
            at, ball, named = at2, ball2, named2
        names[named] = 10  # "\n"
        named += 1
    if at > 1:
        numbers[at - 1] = 93  # the last comma becomes "]"
    return at, named
