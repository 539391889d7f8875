"""Finding JSON objects in free model text: the paper's first-balanced-``{...}`` rule.

A reply may wrap its answer in prose, code fences or a chain of thought that itself contains
braces. :func:`balanced_objects` yields every top-level balanced ``{...}`` substring, matching
braces outside JSON strings only, so a ``}`` inside ``"a } b"`` does not close an object. The
search is one pass (linear in the reply, so a reply of 30,000 unclosed ``{`` costs no more than
one of 30,000 letters) and replies over :data:`MAX_REPLY_CHARS` are refused outright.
:func:`extract` applies the rule that fits the prompt:

- ``first``: without chain of thought, the first balanced object must validate (the paper's rule);
- ``last-valid``: with chain of thought, the last balanced object that validates wins, so a
  sketch of the format in the reasoning does not shadow the final answer.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

from bpb_core.errors import ParseFailure

T = TypeVar("T")
RULE_FIRST = "first"
RULE_LAST_VALID = "last-valid"
MAX_REPLY_CHARS = 1_048_576
"""Longer replies are a parse failure at once (no answer of any task is near this long)."""
MAX_OBJECTS = 200
"""Candidates kept, from the left: a reply holding more top-level objects is not an answer."""
MAX_BRACES = 10_000
"""Runs of braces (``{{{`` is one run) looked at before the search stops: bounds the work on
text made of braces; an answer with its reasoning holds a few hundred."""
# Inside an object: skip (possessively, so a failed match never backtracks) everything but
# braces and quotes, and whole JSON strings, up to the next brace. No match: a string that
# never closes, or no brace left; either way nothing open can close any more.
_NEXT_BRACE = re.compile(r'[^{}"]*+(?:"[^"\\]*+(?:\\.[^"\\]*+)*+"[^{}"]*+)*+([{}])', re.S)
_RUN = re.compile(r"\{+|\}+")


class _Scan:
    """Brace matching over runs of equal braces, keeping only the top-level closed objects.

    ``opened`` holds runs of open braces as ``[first position, count]``; ``levels`` holds, by
    rising depth, the closed objects found at that depth. Closing an object drops the levels
    deeper than it (objects inside it are not top-level).
    """

    def __init__(self) -> None:
        self.opened: list[list[int]] = []
        self.depth = 0
        self.levels: list[tuple[int, list[tuple[int, int]]]] = [(0, [])]

    def open(self, index: int, count: int) -> None:
        self.opened.append([index, count])
        self.depth += count

    def close(self, index: int, count: int) -> int:
        """Close up to ``count`` braces at ``index``; returns how many closed."""
        closed = left = min(count, self.depth)
        outer = index
        while left:
            run = self.opened[-1]
            if run[1] <= left:
                self.opened.pop()
                left -= run[1]
                outer = run[0]
            else:
                run[1] -= left
                outer, left = run[0] + run[1], 0
        self.depth -= closed
        while self.levels[-1][0] > self.depth:
            self.levels.pop()
        if self.levels[-1][0] < self.depth:
            self.levels.append((self.depth, []))
        self.levels[-1][1].append((outer, index + closed))
        return closed

    def spans(self) -> list[tuple[int, int]]:
        return sorted(span for _, level in self.levels for span in level)[:MAX_OBJECTS]


def _spans(text: str) -> list[tuple[int, int]]:
    """``(start, end)`` of the top-level balanced objects, in one pass over ``text`` (bounded
    by :data:`MAX_BRACES`). Braces left open at the end never close; the objects inside them are
    top-level, as if the scan had resumed after each unclosed brace."""
    scan = _Scan()
    position = 0
    for _ in range(MAX_BRACES):
        if len(scan.levels[0][1]) >= MAX_OBJECTS:
            break
        if scan.depth:
            found = _NEXT_BRACE.match(text, position)
            if found is None:
                break
            index = found.start(1)
        else:  # outside every object only an opening brace matters (quotes are prose)
            index = text.find("{", position)
            if index < 0:
                break
        run = _RUN.match(text, index)
        assert run is not None  # index is at a brace
        count = run.end() - index
        if text[index] == "{":
            scan.open(index, count)
            position = run.end()
        else:
            position = index + scan.close(index, count)
    return scan.spans()


def balanced_objects(text: str) -> Iterator[str]:
    """Yield the top-level balanced ``{...}`` substrings of ``text`` from left to right (at most
    :data:`MAX_OBJECTS`); an opening brace that never closes is skipped, so an unterminated
    fragment in the reasoning does not hide a later complete answer."""
    for start, end in _spans(text):
        yield text[start:end]


def _decode(candidate: str) -> Any:
    try:
        return json.loads(candidate)
    except (ValueError, RecursionError) as exc:
        raise ParseFailure(f"not valid JSON: {exc}") from None


def extract(text: str, validate: Callable[[Any], T], *, cot: bool) -> tuple[T, str]:
    """Find the answer object in ``text`` and validate it.

    Args:
        text: The model's reply.
        validate: Turns a decoded JSON value into the answer or raises :class:`ParseFailure`.
        cot: The prompt asked for reasoning first: use the last object that validates.

    Returns:
        The validated answer and the rule that matched (``first`` or ``last-valid``).

    Raises:
        ParseFailure: No balanced object, or none that validates; the message says why.
    """
    if not isinstance(text, str):
        raise ParseFailure("reply is not text")
    if len(text) > MAX_REPLY_CHARS:
        raise ParseFailure(
            f"reply too long: {len(text):,} characters (at most {MAX_REPLY_CHARS:,})"
        )
    candidates = list(balanced_objects(text))
    if not candidates:
        raise ParseFailure("no balanced {...} object in the reply")
    if not cot:
        return validate(_decode(candidates[0])), RULE_FIRST
    last_error = ""
    for candidate in reversed(candidates):
        try:
            return validate(_decode(candidate)), RULE_LAST_VALID
        except ParseFailure as exc:
            last_error = str(exc)
    raise ParseFailure(f"no object in the reply validates (last error: {last_error})")
