"""The compiled scan of scene texts gives exactly what decoding them one by one gives."""

from __future__ import annotations

import json
import re
from typing import Any

import numpy as np
import pytest

from bpb_tasks.billiards.bench_compare import random_scene

pytest.importorskip("numba")
pytest.importorskip("msgspec")


def _by_member(groups: list[Any]) -> dict[int, tuple[Any, ...]]:
    """Each grouped text's values, by its position: horizon, id text, parts, ids, centres and
    velocities (as bytes, so -0.0 and 0.0 differ)."""
    found = {}
    for g in groups:
        for row, member in enumerate(g.members):
            found[member] = (
                g.horizons[row].tobytes(),
                g.names[row],
                g.parts,
                g.ids[row].tobytes(),
                np.ascontiguousarray(g.pos[row]).tobytes(),
                np.ascontiguousarray(g.vel[row]).tobytes(),
            )
    return found


def _same_as_decoded(texts: list[bytes]) -> dict[int, tuple[Any, ...]]:
    from bpb_tasks.billiards.scene_scan import text_groups
    from bpb_tasks.billiards.scene_text import decoded_groups

    fast = _by_member(text_groups(texts))
    assert fast == _by_member(decoded_groups(texts))
    return fast


def _base(seed: int, i: int) -> bytes:
    return random_scene(seed, i, speeds=(0.1, 6.0)).model_dump_json().encode()


def test_the_scan_takes_what_the_models_write_and_gives_the_decoded_values() -> None:
    from bpb_tasks.billiards.scene_scan import scanned_groups

    texts = [_base(31, i) for i in range(300)]
    spaced = [json.dumps(json.loads(t), indent=1).encode() for t in texts[:50]]
    assert scanned_groups(texts)[1] == []  # every text the models write is scanned
    assert scanned_groups(spaced)[1] == []  # and pretty-printed ones
    # parts written another way than the first scene's go the decoded way
    assert scanned_groups(texts[:1] + spaced)[1] == list(range(1, 51))
    assert len(_same_as_decoded(texts + spaced)) == 350


def test_texts_the_scan_leaves_go_the_decoded_way_with_the_same_values() -> None:
    from bpb_tasks.billiards.scene_scan import scanned_groups

    base = _base(32, 0)
    edits = {
        "unicode id": base.replace(b'"scene_id":"', b'"scene_id":"\xc3\xbc', 1),
        "escaped id": base.replace(b'"scene_id":"', b'"scene_id":"\\u0041', 1),
        "keys in another order": base.replace(b'{"scene_id"', b'{"horizon":2.0,"scene_id"', 1),
        "no vel": base.replace(b',"vel":[0.0,0.0]', b"", 1),
        "id with a sign": base.replace(b'"id":1,', b'"id":-1,', 1),
        "id with a leading zero": base.replace(b'"id":1,', b'"id":01,', 1),
        "id too large": base.replace(b'"id":1,', b'"id":2147483648,', 1),
        "largest id": base.replace(b'"id":1,', b'"id":2147483647,', 1),
        "number as a string": base.replace(b'"horizon":', b'"horizon":"1"', 1),
        "exponents": base.replace(b'"vel":[0.0,0.0]', b'"vel":[1E-3,-2e+0]', 1),
        "integers": base.replace(b'"vel":[0.0,0.0]', b'"vel":[0,-0]', 1),
        "another table": base.replace(b'"width":2.0', b'"width":2.5', 1),
        "no pockets": base.replace(b'"pockets":', b'"other":', 1),
        "trailing text": base + b" x",
        "trailing newline": base + b"\n",
        "cut short": base[:-2],
        "no balls": base[: base.index(b'"balls":[') + 9] + b"]}",
        "horizon zero": re.sub(rb'"horizon":[^,]*', b'"horizon":0.0', base, count=1),
        "horizon below zero": re.sub(rb'"horizon":[^,]*', b'"horizon":-1.5', base, count=1),
    }
    names = ["base", *edits, "base again"]
    texts = [base, *edits.values(), base]
    left = scanned_groups(texts)[1]
    scanned = {name for i, name in enumerate(names) if i not in left}
    assert scanned == {
        "base", "largest id", "exponents", "integers", "trailing newline", "base again",
        "horizon zero", "horizon below zero",
    }  # fmt: skip
    found = _same_as_decoded(texts).keys()
    assert {0, 1, 2, len(texts) - 1} <= found  # the id edits read too
    assert names.index("horizon zero") not in found  # scanned, then refused by the checks
    assert names.index("horizon below zero") not in found
    # a number out of float range or not a number sends the whole chunk the decoded way
    for bad in (b'"horizon":1e999', b'"horizon":1.2.'):
        odd = base.replace(b'"horizon":', bad, 1).replace(bad + b"1.0", bad, 1)
        assert scanned_groups([base, odd, base])[1] == [0, 1, 2]
        assert _same_as_decoded([base, odd, base]).keys() == {0, 2}


def test_arbitrary_edits_of_a_text_give_the_decoded_values() -> None:
    from hypothesis import given, settings, strategies as st

    texts = [_base(33, i) for i in range(4)]
    pieces = [b" ", b"\n", b",", b":", b"{", b"}", b"[", b"]", b'"', b"\\", b"0", b"-", b"e", b".",
              b"1e400", b'"id":', b"\xc3\xa9", b"\x00"]  # fmt: skip

    @settings(max_examples=400, deadline=None)
    @given(
        st.integers(0, 3),
        st.lists(
            st.tuples(st.floats(0, 0.999), st.integers(0, 3), st.sampled_from(pieces)),
            min_size=1,
            max_size=3,
        ),
    )
    def check(which: int, edits: list[tuple[float, int, bytes]]) -> None:
        text = bytearray(texts[which])
        for where, cut, piece in edits:
            at = int(where * len(text))
            text[at : at + cut] = piece
        _same_as_decoded([texts[0], bytes(text), texts[1]])

    check()


def test_the_compiled_plain_check_decides_every_scene_as_the_array_one() -> None:
    """The scan path's compiled check keeps and drops exactly the scenes the numpy check does:
    valid scenes with a ball moved onto, or one step of a double beside, a bound (table span,
    pocket reach, a touching ball, the speed limit), NaN, infinities, bad horizons, and ids out
    of order or not starting at 0."""
    from hypothesis import given, settings, strategies as st

    from bpb_tasks.billiards.scene_scan import compiled_plain
    from bpb_tasks.billiards.scene_text import SceneGroup, plain_limits, plain_mask

    scenes = [random_scene(41, i, speeds=(0.1, 6.0)) for i in range(6)]
    parts = (scenes[0].table, scenes[0].physics, scenes[0].pockets)
    lim = plain_limits(SceneGroup([], np.zeros(0), [], parts, *[np.zeros((0, 1, 2))] * 3))
    reach, least = float(np.sqrt(lim.reach2)), float(np.sqrt(lim.least2))

    def beside(v: float, step: int) -> float:
        return float(v if step == 0 else np.nextafter(v, np.inf if step > 0 else -np.inf))

    edit = st.tuples(
        st.sampled_from(["low", "x_high", "y_high", "pocket", "touch", "speed", "nan", "inf"]),
        st.integers(0, 6),  # the ball
        st.integers(-1, 1),  # on the bound, or one double below or above it
        st.integers(0, 5),  # a pocket, or the ball touched
    )

    @settings(max_examples=300, deadline=None)
    @given(
        st.lists(
            st.tuples(
                st.integers(0, 5),
                st.lists(edit, max_size=2),
                st.sampled_from(["ok", "ok", "shuffled", "from 1", 0.0, np.nan, -np.inf]),
            ),
            min_size=1,
            max_size=6,
        )
    )
    def check(rows: list[tuple[int, list[tuple[str, int, int, int]], object]]) -> None:
        k, n = len(rows), len(scenes[0].balls)
        ids = np.tile(np.arange(n), (k, 1))
        pos = np.array([[b.pos for b in scenes[s].balls] for s, _, _ in rows], dtype=float)
        vel = np.array([[b.vel for b in scenes[s].balls] for s, _, _ in rows], dtype=float)
        horizons = np.ones(k)
        for r, (_, edits, how) in enumerate(rows):
            if how == "shuffled":
                ids[r] = ids[r][::-1]
            elif how == "from 1":
                ids[r] += 1
            elif isinstance(how, float):
                horizons[r] = how
            for kind, b, step, other in edits:
                if kind in ("low", "x_high", "y_high"):  # mid-side, away from pockets
                    axis = int(kind == "y_high" or (kind == "low" and other % 2 == 1))
                    pos[r, b] = (0.5, 0.5) if axis else (1.0, 0.5)
                    pos[r, b, axis] = beside(getattr(lim, kind), step)
                elif kind == "pocket":  # into the table: at a side pocket of y = 0, exactly
                    cx, cy = lim.centres[other]
                    pos[r, b] = (cx, beside(cy + reach if cy < 0.5 else cy - reach, step))
                elif kind == "touch" and other != b:  # near, not on: sums round
                    pos[r, b] = (beside(pos[r, other, 0] + least, step), pos[r, other, 1])
                elif kind == "speed":
                    vel[r, b] = (beside(float(np.sqrt(lim.speed2)), step), 0.0)
                else:
                    pos[r, b, step & 1] = np.nan if kind == "nan" else np.inf * (step or 1)
        group = SceneGroup(list(range(k)), horizons, ["x"] * k, parts, ids, pos, vel)
        assert compiled_plain(group).tolist() == plain_mask(group).tolist()

    check()
