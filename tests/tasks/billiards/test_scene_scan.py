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
