"""Finding JSON objects in free model text: the paper's first-balanced-``{...}`` rule.

A reply may wrap its answer in prose, code fences or a chain of thought that itself contains
braces (LaTeX's ``\\frac{a}{b}`` by the hundred). Inside an object, braces are matched outside
JSON strings only, so a ``}`` inside ``"a } b"`` does not close an object; outside every object
a quote is prose. A brace that never finds its match is skipped: the objects inside it count as
top-level. Every top-level object is a candidate, however many there are; the search is one
pass over the reply, linear in its length, and stops at the object that decides. Replies over
:data:`MAX_REPLY_CHARS` are refused outright. :func:`extract` applies the rule that fits the
prompt:

- ``first``: without chain of thought, the first balanced object must validate (the paper's
  rule); the pass runs from the left.
- ``last-valid``: with chain of thought, the last balanced object that validates wins, so a
  sketch of the format in the reasoning does not shadow the final answer. The pass runs from
  the right (over the reversed reply), so the answer is reached before the reasoning, and
  nothing in the reasoning (an unclosed brace, an odd quote) can hide it.
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
# Inside an object: skip (possessively, so a failed match never backtracks) everything but
# braces and quotes, and whole JSON strings, up to the next run of equal braces. No match: a
# string that never closes, or no brace left; either way nothing open can close any more.
_FORWARD = re.compile(r'[^{}"]*+(?:"[^"\\]*+(?:\\.[^"\\]*+)*+"[^{}"]*+)*+(\{++|\}++)', re.S)
# The same over the reversed reply: read backwards, a string ends at the first quote that no
# odd run of backslashes follows (an odd run before a quote escapes it in the reply).
_BACKWARD = re.compile(
    r'[^{}"]*+(?:"(?:[^"]++|"(?=(?:\\\\)*+\\(?!\\)))*+"[^{}"]*+)*+(\{++|\}++)', re.S
)
# A JSON object opens with a key or closes at once: other groups ({a}, {{x}}) are not decoded.
_OBJECT_START = re.compile(r'\{[ \t\n\r]*+["}]')
_RUN = {"{": re.compile(r"(\{++)"), "}": re.compile(r"(\}++)")}


def _close(opened: list[range], count: int) -> int:
    """Close the last ``count`` open braces (no more than are open) of the runs ``opened``;
    returns the position of the outermost brace closed."""
    while count > len(opened[-1]):
        count -= len(opened.pop())
    run = opened.pop()
    if count < len(run):
        opened.append(run[:-count])
    return run[-count]


def _spans(text: str, opener: str, inside: re.Pattern[str]) -> Iterator[tuple[int, int]]:
    """Yield ``(start, end)`` of the top-level balanced objects of ``text`` in text order.

    An object is yielded as soon as its closing brace brings the depth back to 0; the objects
    held inside a brace still open are yielded at the end, when that brace is known never to
    close (nothing after it is at depth 0, so the order holds). ``opener`` is ``{`` for the
    reply, ``}`` for the reversed reply. A run of equal braces (``{{{``, a model's repetition
    loop) is one step: of the objects a run of closing braces ends, only the outermost can be
    top-level.
    """
    run = _RUN[opener]
    opened: list[range] = []  # the runs of open braces
    depth = 0
    held: list[tuple[int, int]] = []  # outermost objects closed inside the open braces
    position = 0
    while True:
        if opened:
            found = inside.match(text, position)
        else:  # outside every object only an opening brace matters (quotes are prose)
            index = text.find(opener, position)
            found = None if index < 0 else run.match(text, index)
        if found is None:
            break
        index, position = found.span(1)
        if text[index] == opener:
            opened.append(range(index, position))
            depth += position - index
            continue
        closed = min(position - index, depth)
        depth -= closed
        start, position = _close(opened, closed), index + closed  # the rest close nothing
        while held and held[-1][0] > start:  # closed inside this one: not top-level
            held.pop()
        if opened:
            held.append((start, position))
        else:
            yield start, position
    yield from held


def _from_the_right(text: str) -> Iterator[tuple[int, int]]:
    """The top-level balanced objects of ``text``, last first."""
    size = len(text)
    for start, end in _spans(text[::-1], "}", _BACKWARD):
        yield size - end, size - start


def balanced_objects(text: str) -> Iterator[str]:
    """Yield the top-level balanced ``{...}`` substrings of ``text`` from left to right, however
    many; an opening brace that never closes is skipped, so an unterminated fragment in the
    reasoning does not hide a later complete answer."""
    for start, end in _spans(text, "{", _FORWARD):
        yield text[start:end]


def _decode(candidate: str) -> Any:
    try:
        return json.loads(candidate)
    except (ValueError, RecursionError) as exc:
        raise ParseFailure(f"not valid JSON: {exc}") from None


def _last_valid(text: str, validate: Callable[[Any], T]) -> T:
    tried: set[str] = set()  # reasoning repeats itself: each distinct object is tried once
    last_error = ""
    for start, end in _from_the_right(text):
        candidate = text[start:end]
        if candidate in tried:
            continue
        tried.add(candidate)
        if not _OBJECT_START.match(candidate):
            continue
        try:
            return validate(_decode(candidate))
        except ParseFailure as exc:
            last_error = str(exc)
    if not tried:
        raise ParseFailure("no balanced {...} object in the reply")
    last_error = last_error or "none is a JSON object"
    raise ParseFailure(f"no object in the reply validates (last error: {last_error})")


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
    if cot:
        return _last_valid(text, validate), RULE_LAST_VALID
    first = next(balanced_objects(text), None)
    if first is None:
        raise ParseFailure("no balanced {...} object in the reply")
    return validate(_decode(first)), RULE_FIRST
