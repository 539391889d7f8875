"""Finding JSON objects in free model text: the paper's first-balanced-``{...}`` rule.

A reply may wrap its answer in prose, code fences or a chain of thought that itself contains
braces (LaTeX's ``\\frac{a}{b}`` by the hundred). :func:`balanced_objects` yields every top-level
balanced ``{...}`` substring, however many, matching braces outside JSON strings only, so a
``}`` inside ``"a } b"`` does not close an object. The search is linear in the reply: array
operations over the positions of braces and quotes (:func:`_array_spans`); only a reply where a
string inside an object holds a brace takes the plain scan (:class:`_Scan`, the reference),
which looks at up to :data:`MAX_BRACES` runs of braces. Replies over :data:`MAX_REPLY_CHARS` are
refused outright.
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

import numpy as np
import numpy.typing as npt

from bpb_core.errors import ParseFailure

T = TypeVar("T")
RULE_FIRST = "first"
RULE_LAST_VALID = "last-valid"
MAX_REPLY_CHARS = 1_048_576
"""Longer replies are a parse failure at once (no answer of any task is near this long)."""
MAX_BRACES = 10_000
"""Runs of braces (``{{{`` is one run) the plain scan looks at before it stops: it bounds the
work on a reply whose strings hold braces; the array search has no such bound."""
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
        return sorted(span for _, level in self.levels for span in level)


def _scanned_spans(text: str) -> list[tuple[int, int]]:
    """``(start, end)`` of the top-level balanced objects, in one plain pass over ``text``
    (bounded by :data:`MAX_BRACES`). Braces left open at the end never close; the objects inside
    them are top-level, as if the scan had resumed after each unclosed brace."""
    scan = _Scan()
    position = 0
    for _ in range(MAX_BRACES):
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


Ints = npt.NDArray[np.int64]
Codes = npt.NDArray[np.uint8] | npt.NDArray[np.uint32]


def _codes(text: str) -> Codes:
    """The characters of ``text`` as numbers, one per character (a byte each when ASCII)."""
    if text.isascii():
        return np.frombuffer(text.encode("ascii"), dtype=np.uint8)
    return np.frombuffer(text.encode("utf-32-le"), dtype=np.uint32)


def _before(sorted_at: Ints, at: Ints) -> Ints:
    """For each position of ``at``, how many of ``sorted_at`` lie before it."""
    return np.searchsorted(sorted_at, at).astype(np.int64)


def _counted_braces(codes: Codes) -> tuple[Ints, Ints, Ints]:
    """Positions, steps (+1 open, -1 close) and depth after each brace that counts: a ``}`` with
    nothing open is prose. Strings are not looked at here."""
    at = np.flatnonzero((codes == 123) | (codes == 125))
    step = (codes[at] == 123).astype(np.int64) * 2 - 1
    raw = np.cumsum(step)
    if not raw.size or raw.min() >= 0:  # no '}' ever finds nothing open
        return at, step, raw
    floor = np.minimum.accumulate(np.minimum(raw, 0))  # falls only where a '}' finds depth 0
    counted = ~((step < 0) & (np.diff(floor, prepend=0) < 0))
    return at[counted], step[counted], (raw - floor)[counted]


def _depth_at(at: Ints, depth: Ints, where: Ints) -> Ints:
    """The brace depth at each position of ``where`` (0 before the first brace)."""
    seen = _before(at, where)
    return np.where(seen > 0, depth[np.maximum(seen - 1, 0)], 0)


def _escaped(codes: Codes, where: Ints) -> npt.NDArray[np.bool_]:
    """Whether an odd run of backslashes stands right before each position of ``where``."""
    plain = np.flatnonzero(codes != 92)
    seen = _before(plain, where)
    previous = np.where(seen > 0, plain[np.maximum(seen - 1, 0)], -1)
    return np.asarray((where - previous - 1) % 2 == 1)


def _strings_hold_no_brace(codes: Codes, at: Ints, depth: Ints) -> bool:
    """Whether the JSON strings inside objects (from each unescaped quote at depth > 0 to the
    next) hold no brace, and every escaped quote at depth > 0 is inside one: then the depths
    computed without looking at strings are the plain scan's."""
    quotes = np.flatnonzero(codes == 34)
    inside = quotes[_depth_at(at, depth, quotes) > 0]
    if not inside.size:
        return True
    escaped = _escaped(codes, inside)
    bounds = inside[~escaped]  # an even count before a position: outside every string
    braces_out = np.all(_before(bounds, at) % 2 == 0)
    return bool(braces_out and np.all(_before(bounds, inside[escaped]) % 2 == 1))


def _array_spans(text: str) -> tuple[Ints, Ints] | None:
    """Starts and ends of the top-level balanced objects by array operations, or ``None`` when
    a string inside an object holds a brace (the plain scan decides those).

    An open brace and the close matching it share a level (the depth inside them); sorted by
    level, then position, each level reads open, close, open, close, ... and at most one last
    open that never closes. A pair is top-level when no pair holds it: at level 1, or after
    the unclosed open of the level below. Those come out of the sort in text order.
    """
    codes = _codes(text)
    at, step, depth = _counted_braces(codes)
    if not _strings_hold_no_brace(codes, at, depth):
        return None
    level = depth + (step < 0)
    order = np.argsort(level, kind="stable")
    at, step, level = at[order], step[order], level[order]
    pair = (step[:-1] > 0) & (step[1:] < 0) & (level[:-1] == level[1:])
    unclosed = (step > 0) & ~np.append(pair, False)
    below = np.full(int(level.max(initial=0)) + 2, np.iinfo(np.int64).max)
    below[0] = -1
    below[level[unclosed]] = at[unclosed]
    starts, ends, levels = at[:-1][pair], at[1:][pair] + 1, level[:-1][pair]
    top = starts > below[levels - 1]
    return starts[top], ends[top]


def _spans(text: str) -> list[tuple[int, int]]:
    found = _array_spans(text)
    if found is None:
        return _scanned_spans(text)
    return list(zip(found[0].tolist(), found[1].tolist(), strict=True))


def balanced_objects(text: str) -> Iterator[str]:
    """Yield the top-level balanced ``{...}`` substrings of ``text`` from left to right, however
    many; an opening brace that never closes is skipped, so an unterminated fragment in the
    reasoning does not hide a later complete answer."""
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
    spans = _spans(text)
    if not spans:
        raise ParseFailure("no balanced {...} object in the reply")
    if not cot:
        start, end = spans[0]
        return validate(_decode(text[start:end])), RULE_FIRST
    last_error, failed = "", set()  # reasoning repeats itself: each distinct object once
    for start, end in reversed(spans):
        candidate = text[start:end]
        if candidate in failed:
            continue
        try:
            return validate(_decode(candidate)), RULE_LAST_VALID
        except ParseFailure as exc:
            last_error = str(exc)
            failed.add(candidate)
    raise ParseFailure(f"no object in the reply validates (last error: {last_error})")
