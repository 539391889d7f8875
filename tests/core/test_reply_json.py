"""The reply extractor: one linear pass, any number of objects, and only ParseFailure escapes."""

from __future__ import annotations

import json
import re
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from bpb_core.errors import ParseFailure
from bpb_core.reply_json import MAX_REPLY_CHARS, balanced_objects, extract

PIECES = ["{", "}", '"', "\\", '\\"', '{"a":', "[", "]", ":", ",", "1" * 50, "x", " ", "{}",
          '"}"', '"{"', "\n", "1e999", "-", "null"]  # fmt: skip

# Adversarial replies: runs of pieces repeated up to 10 MB in all.
replies = st.lists(
    st.tuples(st.sampled_from(PIECES), st.integers(1, 2_000_000)), min_size=1, max_size=6
).map(lambda runs: "".join(piece * count for piece, count in runs)[: 10 * 1024 * 1024])


def _validate(value: Any) -> Any:
    if not isinstance(value, dict):
        raise ParseFailure("not an object")
    return value


def _reference(text: str) -> list[str]:
    """The old quadratic scan (fresh string state at every start), for small texts."""
    out, position = [], 0
    while True:
        start = text.find("{", position)
        if start < 0:
            return out
        depth, in_string, escaped, end = 0, False, False, None
        for i in range(start, len(text)):
            ch = text[i]
            if in_string:
                escaped, in_string = (False, in_string) if escaped else (ch == "\\", ch != '"')
            elif ch == '"':
                in_string = True
            elif ch in "{}":
                depth += 1 if ch == "{" else -1
                if depth == 0:
                    end = i + 1
                    break
        if end is None:
            position = start + 1
            continue
        out.append(text[start:end])
        position = end
    return out


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=replies, cot=st.booleans())
def test_only_parse_failure_escapes_on_adversarial_replies_up_to_10_mb(
    text: str, cot: bool
) -> None:
    try:
        value, rule = extract(text, _validate, cot=cot)
    except ParseFailure:
        return
    assert isinstance(value, dict) and rule in ("first", "last-valid")


@settings(max_examples=300, deadline=None)
@given(text=st.text(alphabet=st.sampled_from('{}"\\ax'), max_size=60))
def test_one_pass_finds_what_the_old_scan_found(text: str) -> None:
    # The old scan restarted after an unclosed brace with a fresh string state; the one pass
    # keeps the state (they differ only on a quote inside a brace that never closes).
    found = list(balanced_objects(text))
    if '"' not in text:
        assert found == _reference(text)
    else:  # quoted text closing every brace: the same objects
        closed = text.count("{") == sum(o.count("{") for o in _reference(text))
        if closed:
            assert found == _reference(text)


def test_braces_inside_strings_and_unclosed_braces() -> None:
    text = 'x {"a": "x } y { z", "b": {"c": 1}} and {"d": 2} { {e} {f'
    assert list(balanced_objects(text)) == [
        '{"a": "x } y { z", "b": {"c": 1}}',
        '{"d": 2}',
        "{e}",
    ]
    assert list(balanced_objects('{"a\\"}" } {"b": "\\\\"}')) == ['{"a\\"}" }', '{"b": "\\\\"}']


def test_a_reply_over_the_size_cap_is_a_parse_failure() -> None:
    answer = json.dumps({"a": 1})
    assert extract("x" * (MAX_REPLY_CHARS - 20) + answer, _validate, cot=False)[0] == {"a": 1}
    with pytest.raises(ParseFailure, match=re.escape(f"at most {MAX_REPLY_CHARS:,}")):
        extract("x" * MAX_REPLY_CHARS + answer, _validate, cot=False)


def test_unclosed_braces_before_the_answer() -> None:
    # The reply that froze a run for 25 s: 30,000 unclosed braces, then the answer.
    text = "{" * 30_000 + ' reasoning... {"a": 1}'
    assert extract(text, _validate, cot=True) == ({"a": 1}, "last-valid")
    # Separate braces, far more than the 10,000 runs the search used to stop at: still found.
    text = "{ " * 200_000 + ' {"a": 1}'
    assert extract(text, _validate, cot=True) == ({"a": 1}, "last-valid")
    assert extract(text, _validate, cot=False) == ({"a": 1}, "first")


@pytest.mark.parametrize(
    "text", ["{{{a}}}}}{{b}", "}}{{{x}{y}}", "{{{{a}} {b}", "{a}}}}{{{{{{c}}", "{{}}{{}{}}}{"]
)
def test_runs_of_braces_match_like_single_braces(text: str) -> None:
    assert list(balanced_objects(text)) == _reference(text)


def _picked(value: Any) -> Any:
    if not isinstance(value, dict) or "pick" not in value:
        raise ParseFailure("no pick")
    return value["pick"]


# Reasoning with braces of every kind: LaTeX groups, an unclosed \left\{, stray closes, odd
# quotes, escapes, format sketches and objects that are not the answer.
NOISE = ["\\frac{a}{b}", "\\left\\{", "}", "{", '"', "\\", '\\"', '{"a": 1}',
         '{"pick": [...]}', '"}"', "{x}", " v_{0}^{2} ", "\n"]  # fmt: skip
REASONING = st.lists(
    st.sampled_from(NOISE)
    | st.text(alphabet=st.sampled_from('{}"\\ax:,[] '), max_size=8)
    | st.text(max_size=8),
    max_size=60,
).map("".join)
# After the answer: prose, a code fence, even an opening brace or a quote; no closing brace.
TRAILING = st.text(alphabet=st.characters(blacklist_characters="}"), max_size=20)


@settings(max_examples=400, deadline=None)
@given(before=REASONING, pick=st.integers(), after=TRAILING, indent=st.sampled_from([None, 2]))
def test_the_answer_after_any_reasoning_with_braces_is_found(
    before: str, pick: int, after: str, indent: int | None
) -> None:
    answer = json.dumps({"note": 'a "}" and a {', "pick": pick}, indent=indent)
    assert extract(before + answer + after, _picked, cot=True) == (pick, "last-valid")


JSON_VALUES = st.recursive(
    st.none() | st.integers() | st.text(alphabet=st.sampled_from('{}"\\ax'), max_size=6),
    lambda inner: st.dictionaries(st.text(max_size=3), inner, max_size=3),
    max_leaves=8,
)
PROSE = st.text(alphabet=st.sampled_from("{}ax \n"), max_size=10)


@settings(max_examples=150, deadline=None)
@given(
    parts=st.lists(
        st.tuples(PROSE, st.dictionaries(st.text(max_size=3), JSON_VALUES, max_size=3)), max_size=6
    )
)
def test_both_directions_try_the_same_objects(parts: list[tuple[str, dict[str, Any]]]) -> None:
    # Objects whose strings hold braces, quotes and backslashes, between bits of quote-free
    # prose with braces: last-valid tries, last first, what the left-to-right pass finds.
    text = "".join(prose + json.dumps(value) for prose, value in parts)
    seen: list[Any] = []

    def refuse(value: Any) -> Any:
        seen.append(value)
        raise ParseFailure("refused")

    with pytest.raises(ParseFailure):
        extract(text, refuse, cot=True)
    distinct = dict.fromkeys(reversed(list(balanced_objects(text))))  # each text once, last first
    assert seen == [json.loads(c) for c in distinct if _decodes(c)]


def _decodes(candidate: str) -> bool:
    try:
        json.loads(candidate)
    except ValueError:
        return False
    return True
