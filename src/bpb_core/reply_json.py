"""Finding JSON objects in free model text: the paper's first-balanced-``{...}`` rule.

A reply may wrap its answer in prose, code fences or a chain of thought that itself contains
braces. :func:`balanced_objects` yields every top-level balanced ``{...}`` substring, matching
braces outside JSON strings only, so a ``}`` inside ``"a } b"`` does not close an object.
:func:`extract` applies the rule that fits the prompt:

- ``first``: without chain of thought, the first balanced object must validate (the paper's rule);
- ``last-valid``: with chain of thought, the last balanced object that validates wins, so a
  sketch of the format in the reasoning does not shadow the final answer.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

from bpb_core.errors import ParseFailure

T = TypeVar("T")
RULE_FIRST = "first"
RULE_LAST_VALID = "last-valid"
_MAX_OBJECTS = 200  # bound the work on adversarial text full of braces


def _object_end(text: str, start: int) -> int | None:
    """Index just past the ``}`` closing the ``{`` at ``start``, or ``None`` if it never closes."""
    depth = 0
    in_string = False
    escaped = False
    for i in range(start, len(text)):
        ch = text[i]
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
            if depth == 0:
                return i + 1
    return None


def balanced_objects(text: str) -> Iterator[str]:
    """Yield top-level balanced ``{...}`` substrings of ``text`` from left to right.

    An opening brace that never closes is skipped and the scan resumes after it, so an
    unterminated fragment in the reasoning does not hide a later complete answer.
    """
    position = 0
    found = 0
    while found < _MAX_OBJECTS:
        start = text.find("{", position)
        if start < 0:
            return
        end = _object_end(text, start)
        if end is None:
            position = start + 1
            continue
        found += 1
        yield text[start:end]
        position = end


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
