"""What every command shares: the rich consoles it writes to, how registry warnings reach the
user, the options several commands take, and terminal tables that fit the console.

Emoji codes are off: adapter specs are ``name:model``, and a line such as ``echo:x: 2 api
errors`` must not print ``echo❌ 2 api errors`` (rich reads ``:x:`` as an emoji code).

``click.FloatRange`` lets ``nan`` through every bound (each comparison with it is false) and
``inf`` through any lower one, so ``--timeout nan`` or ``--rpm inf`` would reach the runner:
:class:`FiniteFloat` refuses both.

Tables fit the console, every value whole, every row's name told apart. A table wider than the
console first shortens its row names from the middle (``gpt-5.…-pro``),
never to names that read alike; when its value columns still do not fit beside the names, it is
printed in parts of whole columns, each part repeating the name and key columns. A value is never
cut (rich's default squeezes a wide table to ``1…``): each column is given the width of its widest
cell, so rich never squeezes it, and its header wraps at spaces instead.
"""

from __future__ import annotations

import functools
import math
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import click
from rich.console import Console
from rich.table import Table
from rich.text import Text

from bpb_core.errors import BadInput

if TYPE_CHECKING:
    from bpb_core.registry import Registry

F = TypeVar("F", bound=Callable[..., Any])

PIPE_WIDTH = 140  # tables piped to a file or a log are not squeezed into 80 columns


@functools.cache
def stdout() -> Console:
    """Console on standard output (140 columns when piped, unless COLUMNS says otherwise)."""
    piped = not sys.stdout.isatty() and "COLUMNS" not in os.environ
    return Console(width=PIPE_WIDTH if piped else None, emoji=False)


@functools.cache
def stderr() -> Console:
    """Console on standard error (progress, warnings)."""
    return Console(stderr=True, emoji=False)


def load_registry() -> Registry:
    """Build the registry and show each plugin warning on stderr as one line."""
    from bpb_core.registry import make_registry

    registry = make_registry(warn=False)
    for line in registry.warnings:
        stderr().print(f"[yellow]warning:[/] {line}", highlight=False, soft_wrap=True)
    return registry


class FiniteFloat(click.FloatRange):
    """A :class:`click.FloatRange` that also refuses ``nan`` and infinities."""

    name = "finite number"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


PATH = click.Path(path_type=Path)
"""The type of a path option or argument (click hands a :class:`~pathlib.Path`)."""


def positive() -> FiniteFloat:
    """A finite number above zero."""
    return FiniteFloat(min=0, min_open=True)


PORT_HELP = "Port on 127.0.0.1 (the apps never listen on other interfaces)."
PORTS = click.IntRange(0, 65535)
"""``--port`` of the commands that serve a web app (``human``, ``view``)."""

input_mode_option = click.option(
    "--input-mode",
    type=click.Choice(["image", "image+state", "state"]),
    default="image",
    show_default=True,
    help="What the model gets: the image, the image and the scene as text, or the text alone.",
)
"""``--input-mode`` of every command that builds prompts (``run``, ``prompt``)."""

force_numeric_option = click.option(
    "--force-numeric", is_flag=True, help="Ask for numbers where a task would allow null."
)
"""``--force-numeric`` of every command that builds prompts (``run``, ``prompt``)."""

horizons_option = click.option(
    "--horizons", help="Comma-separated horizons to include (default: all)."
)
"""``--horizons`` of the commands that select scenes (``run``, ``human``)."""

limit_option = click.option(
    "--limit", type=click.IntRange(min=1), help="First N scenes per horizon."
)
"""``--limit`` of the commands that select scenes (``run``, ``human``)."""


def counted(*decls: str, default: int, low: int = 1, help: str | None = None) -> Callable[[F], F]:
    """An integer option of at least ``low`` whose help shows its default."""
    kind = click.IntRange(min=low)
    return click.option(*decls, type=kind, default=default, show_default=True, help=help)


def pct(value: Any) -> str:
    """A share as ``12.3%``; ``–`` when it is missing (``None`` or NaN)."""
    return "–" if value is None or math.isnan(float(value)) else f"{100 * value:.1f}%"


def csv_list(value: str | None, option: str) -> list[str]:
    """The items of a comma-separated ``option`` (none when it is not given).

    Raises:
        BadInput: The option is given but lists nothing.
    """
    if value is None:
        return []
    items = [v.strip() for v in value.split(",") if v.strip()]
    if not items:
        raise BadInput(f"{option}: empty list")
    return items


def horizons(value: str | None) -> tuple[float, ...] | None:
    """``--horizons`` as numbers (``None``: all horizons).

    Raises:
        BadInput: An item is not a number.
    """
    if value is None:
        return None
    try:
        return tuple(float(h) for h in csv_list(value, "--horizons"))
    except ValueError:
        raise BadInput(f"--horizons: expected numbers like 1,2,3, got {value!r}") from None


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
