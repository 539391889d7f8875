"""The last step of ``bpb simulate``'s fast path: ``final.json`` lines put together as bytes by
compiled code (numba, through the kernel's :func:`~bpb_tasks.simulators.analytic.kernel_roots.jit`).

Numbers are not formatted here: the caller has pydantic-core write every number of a chunk in one
call (so the bytes stay pydantic's), and :func:`assemble` copies each number's text where the line
holds it, between the fixed pieces of :data:`LITERALS` and the ids it writes itself. Putting the
same lines together in Python took two thirds of the fast path's time after the simulation.
"""

from __future__ import annotations

import numpy as np

from bpb_tasks.billiards.scene import WALLS
from bpb_tasks.simulators.analytic.compiled import KINDS  # the kernel's event kinds, in order
from bpb_tasks.simulators.analytic.kernel_roots import jit

if len(KINDS) != 4 or len(WALLS) != 4:  # the indices below are compiled in as constants
    raise RuntimeError("truth_bytes expects four event kinds and four walls")

LITERALS: list[bytes] = [
    b'{"scene_id":',
    b',"horizon":',
    b',"q1":[',
    b'{"id":',
    b',"answer":"T"}',
    b',"answer":"F"}',
    b'],"q2":[',
    b'],"predictions":[',
    b',"pos":[',
    b"]}",
    b',"pos":null}',
    b'],"events":[',
    b'{"t":',
    b'],"wall":null,"positions":[[',
    b"],[",
    b"]]}",
    b'],"stability":null,"simulator":',
    b"}",
    *(f',"kind":"{kind}","ids":['.encode() for kind in KINDS),
    *(f'],"wall":"{wall}","positions":[['.encode() for wall in WALLS),
    *(f'{{"wall":"{wall}","answer":"{answer}"}}'.encode() for wall in WALLS for answer in "TF"),
]
(HEAD, HORIZON, Q1, ID, TRUE, FALSE, Q2, PREDICTIONS, POS, POS_END, POS_NULL) = range(11)
(EVENTS, TIME, WALL_NULL, NEXT, POSITIONS_END, TAIL, END) = range(11, 18)
KIND0, WALL0, Q2_0 = 18, 22, 26  # first of the kinds, walls, and (wall, answer) pairs

_TABLE = np.frombuffer(b"".join(LITERALS), dtype=np.uint8)
_OFFSETS = np.cumsum([0, *map(len, LITERALS)]).astype(np.int64)


def assemble(
    numbers: bytes,
    ids: np.ndarray,
    alive: np.ndarray,
    hits: np.ndarray,
    walls: np.ndarray,
    events: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    scene_ids: list[str],
    simulator: str,
) -> bytes:
    """The lines of ``k`` scenes of ``n`` balls, joined by newlines (UTF-8).

    Args:
        numbers: pydantic-core's JSON of one flat list: the ``k`` horizons, the ``2kn`` final
            coordinates (rounded), then ``(t, xa, ya, xb, yb)`` of each event.
        ids: ``(k, n)`` ball ids, ascending per scene (the cue ball, id 0, first).
        alive: ``(k * n,)`` whether each ball is still on the table.
        hits: ``(k, n)`` whether the cue ball touched each ball.
        walls: ``(k,)`` the walls the cue ball touched, as bits in :data:`WALLS` order.
        events: per event, sorted by scene: kind, first and second ball id (-1: none), wall
            index (-1: none), and the ``k + 1`` bounds of each scene's events.
        scene_ids: each scene's id as JSON text (quoted, escaped).
        simulator: the simulator's name as JSON text.
    """
    sids = "".join(scene_ids)
    raw = sids.encode()
    sizes = map(len, scene_ids) if len(raw) == len(sids) else (len(s.encode()) for s in scene_ids)
    bounds = np.zeros(len(scene_ids) + 1, dtype=np.int64)
    np.cumsum(np.fromiter(sizes, np.int64, len(scene_ids)), out=bounds[1:])
    out, size = _assemble(
        np.frombuffer(numbers, dtype=np.uint8),
        ids,
        alive,
        hits,
        walls,
        *events,
        np.frombuffer(raw, dtype=np.uint8),
        bounds,
        np.frombuffer(simulator.encode(), dtype=np.uint8),
        _TABLE,
        _OFFSETS,
    )
    return out[:size].tobytes()


@jit
def put(out: np.ndarray, at: int, table: np.ndarray, start: int, end: int) -> int:
    """Copy ``table[start:end]`` to ``out[at:]``; unsigned indices spare numba the check for
    negative ones on every byte (three times faster)."""
    to = np.uint64(at)
    for p in range(np.uint64(start), np.uint64(end)):
        out[to] = table[p]
        to += np.uint64(1)
    return np.int64(to)  # type: ignore[return-value]  # an int in compiled code


@jit
def _byte(out: np.ndarray, at: int, value: int) -> int:
    out[np.uint64(at)] = value
    return at + 1


@jit
def _lit(out: np.ndarray, at: int, table: np.ndarray, offsets: np.ndarray, which: int) -> int:
    return put(out, at, table, offsets[which], offsets[which + 1])


@jit
def _int(out: np.ndarray, at: int, value: int) -> int:
    """``value`` (>= 0) in decimal."""
    digits = 1
    rest = value
    while rest >= 10:
        rest //= 10
        digits += 1
    for d in range(digits - 1, -1, -1):
        out[np.uint64(at + d)] = 48 + value % 10
        value //= 10
    return at + digits


@jit
def _assemble(
    text: np.ndarray,
    ids: np.ndarray,
    alive: np.ndarray,
    hits: np.ndarray,
    walls: np.ndarray,
    kind: np.ndarray,
    first: np.ndarray,
    second: np.ndarray,
    wall: np.ndarray,
    bounds: np.ndarray,
    sid: np.ndarray,
    sid_at: np.ndarray,
    sim: np.ndarray,
    table: np.ndarray,
    offsets: np.ndarray,
) -> tuple[np.ndarray, int]:
    k, n = ids.shape
    m = kind.shape[0]
    starts = np.empty(k + 2 * k * n + 5 * m + 1, dtype=np.int64)  # number c: starts[c]..[c+1]-1
    starts[0] = 1
    c = np.uint64(0)
    for p in range(np.uint64(1), np.uint64(text.shape[0])):
        if text[p] == 44 or text[p] == 93:  # "," or the closing "]"
            c += np.uint64(1)
            starts[c] = p + np.uint64(1)
    size = text.shape[0] + sid.shape[0] + k * (sim.shape[0] + 600 + 120 * n) + 200 * m
    out = np.empty(size, dtype=np.uint8)
    at = 0
    xy, ev = k, k + 2 * k * n
    for j in range(k):
        if j:
            at = _byte(out, at, 10)
        at = _lit(out, at, table, offsets, HEAD)
        at = put(out, at, sid, sid_at[j], sid_at[j + 1])
        at = _lit(out, at, table, offsets, HORIZON)
        at = put(out, at, text, starts[j], starts[j + 1] - 1)
        at = _lit(out, at, table, offsets, Q1)
        for i in range(1, n):
            if i > 1:
                at = _byte(out, at, 44)
            at = _lit(out, at, table, offsets, ID)
            at = _int(out, at, ids[j, i])
            at = _lit(out, at, table, offsets, TRUE if hits[j, i] else FALSE)
        at = _lit(out, at, table, offsets, Q2)
        for w in range(4):
            if w:
                at = _byte(out, at, 44)
            at = _lit(out, at, table, offsets, Q2_0 + 2 * w + (0 if walls[j] >> w & 1 else 1))
        at = _lit(out, at, table, offsets, PREDICTIONS)
        for i in range(n):
            if i:
                at = _byte(out, at, 44)
            at = _lit(out, at, table, offsets, ID)
            at = _int(out, at, ids[j, i])
            b = j * n + i
            if alive[b]:
                at = _lit(out, at, table, offsets, POS)
                at = put(out, at, text, starts[xy + 2 * b], starts[xy + 2 * b + 1] - 1)
                at = _byte(out, at, 44)
                at = put(out, at, text, starts[xy + 2 * b + 1], starts[xy + 2 * b + 2] - 1)
                at = _lit(out, at, table, offsets, POS_END)
            else:
                at = _lit(out, at, table, offsets, POS_NULL)
        at = _lit(out, at, table, offsets, EVENTS)
        for e in range(bounds[j], bounds[j + 1]):
            if e > bounds[j]:
                at = _byte(out, at, 44)
            base = ev + 5 * e
            at = _lit(out, at, table, offsets, TIME)
            at = put(out, at, text, starts[base], starts[base + 1] - 1)
            pair = second[e] >= 0
            at = _lit(out, at, table, offsets, KIND0 if pair else KIND0 + kind[e])
            at = _int(out, at, first[e])
            if pair:
                at = _byte(out, at, 44)
                at = _int(out, at, second[e])
            named = not pair and wall[e] >= 0
            at = _lit(out, at, table, offsets, WALL0 + wall[e] if named else WALL_NULL)
            at = put(out, at, text, starts[base + 1], starts[base + 2] - 1)
            at = _byte(out, at, 44)
            at = put(out, at, text, starts[base + 2], starts[base + 3] - 1)
            if pair:
                at = _lit(out, at, table, offsets, NEXT)
                at = put(out, at, text, starts[base + 3], starts[base + 4] - 1)
                at = _byte(out, at, 44)
                at = put(out, at, text, starts[base + 4], starts[base + 5] - 1)
            at = _lit(out, at, table, offsets, POSITIONS_END)
        at = _lit(out, at, table, offsets, TAIL)
        at = put(out, at, sim, 0, sim.shape[0])
        at = _lit(out, at, table, offsets, END)
    return out, at
