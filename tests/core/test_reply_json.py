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
