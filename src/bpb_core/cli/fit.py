"""Terminal tables that fit the console: every value whole, every row's name told apart.

A table wider than the console first shortens its row names from the middle (``gpt-5.…-pro``),
never to names that read alike; when its value columns still do not fit beside the names, it is
printed in parts of whole columns, each part repeating the name and key columns. A value is never
cut (rich's default squeezes a wide table to ``1…``): each column is given the width of its widest
cell, so rich never squeezes it, and its header wraps at spaces instead.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from rich.console import Console
from rich.table import Table
from rich.text import Text

MIN_NAME = 12
"""The fewest characters a name is shortened to; a table needing shorter names is split."""
ELLIPSIS = "…"


@dataclass(frozen=True)
class Name:
    """A row's name cell: ``text`` (shortened when the table must) then ``suffix`` (kept
    whole, such as `` (baseline)``), both drawn in ``style``."""

    text: str
    suffix: str = ""
    style: str = ""


def print_fitted(
    console: Console,
    title: str,
    head: Sequence[str],
    rows: Sequence[tuple[Name, Sequence[str]]],
    *,
    keys: int = 0,
) -> None:
    """Print a table of ``rows`` (a name and the markup of the other cells, in ``head``'s order
    after the name's header) within ``console``'s width; the first ``keys`` cells after the name
    (a task column) are repeated in every part of a split table."""
    for table in fitted(title, head, rows, console.width, keys=keys):
        console.print(table)


def fitted(
    title: str,
    head: Sequence[str],
    rows: Sequence[tuple[Name, Sequence[str]]],
    width: int,
    *,
    keys: int = 0,
) -> list[Table]:
    """The tables :func:`print_fitted` prints: one, or parts of the value columns, each at most
    ``width`` wide (wider only where the names at :data:`MIN_NAME` and the widest value column
    alone do not fit)."""
    cells = [[Text.from_markup(c) for c in row] for _, row in rows]
    names = [name for name, _ in rows]
    widest = [max((row[j].cell_len for row in cells), default=0) for j in range(len(head) - 1)]
    whole = [max(w, len(header)) for w, header in zip(widest, head[1:], strict=True)]
    first = max([len(head[0]), *(len(n.text) + len(n.suffix) for n in names)])
    if sum(whole) + 3 * len(head) + 1 + first <= width:  # every header stays whole
        widths = whole
    else:  # headers wrap at spaces
        words = (max(map(len, header.split()), default=0) for header in head[1:])
        widths = [max(w, word) for w, word in zip(widest, words, strict=True)]
    fixed = sum(widths[:keys]) + 3 * (keys + 1) + 1  # rich: 3 a column (padding, rule), 1 edge
    values = list(range(keys, len(widths)))
    size, parts = _layout(names, head[0], [widths[j] for j in values], width - fixed)
    labels = [_shortened(n.text, size) + n.suffix for n in names]
    name_width = max([len(head[0]), *map(len, labels)])
    tables: list[Table] = []
    for part in ([values[k] for k in p] for p in parts):
        table = Table(title=title if not tables else f"{title} (continued)")
        table.add_column(head[0], justify="left", width=name_width)
        for j in [*range(keys), *part]:
            table.add_column(head[j + 1], justify="left" if j < keys else "right", width=widths[j])
        for name, label, row in zip(names, labels, cells, strict=True):
            table.add_row(Text(label, style=name.style), *(row[j] for j in [*range(keys), *part]))
        tables.append(table)
    return tables


def _layout(
    names: Sequence[Name], header: str, widths: list[int], room: int
) -> tuple[int, list[list[int]]]:
    """The names' shortened size and the value columns' parts (indices into ``widths``) for
    ``room`` columns beside the key columns: the fewest parts, then the longest names."""
    longest = max((len(n.text) for n in names), default=0)
    least = _distinct_size(names, min(MIN_NAME, longest))
    best: tuple[int, list[list[int]]] | None = None
    for size in range(max(longest, least), least - 1, -1):
        labels = (len(_shortened(n.text, size)) + len(n.suffix) for n in names)
        parts = _parts(widths, room - max([len(header), *labels]))
        if best is None or len(parts) < len(best[1]):
            best = size, parts
    assert best is not None
    return best


def _parts(widths: list[int], budget: int) -> list[list[int]]:
    """The columns of ``widths`` (their indices) in runs that fit in ``budget``, in order."""
    parts: list[list[int]] = [[]]
    used = 0
    for j, w in enumerate(widths):
        if parts[-1] and used + w + 3 > budget:
            parts.append([])
            used = 0
        parts[-1].append(j)
        used += w + 3
    return parts


def _distinct_size(names: Sequence[Name], size: int) -> int:
    """The shortest length from ``size`` up at which the shortened names stay distinct."""
    texts = [n.text for n in names]
    want = len(set(texts))
    longest = max((len(t) for t in texts), default=0)
    while size < longest and len({_shortened(t, size) for t in texts}) < want:
        size += 1
    return size


def _shortened(text: str, size: int) -> str:
    """``text`` at most ``size`` characters, its middle replaced by an ellipsis."""
    if len(text) <= size:
        return text
    head = size // 2
    tail = size - 1 - head
    return text[:head] + ELLIPSIS + (text[-tail:] if tail else "")
