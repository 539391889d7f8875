"""Options several commands share, their parsing, and the option types click lacks.

``click.FloatRange`` lets ``nan`` through every bound (each comparison with it is false) and
``inf`` through any lower one, so ``--timeout nan`` or ``--rpm inf`` would reach the runner:
:class:`FiniteFloat` refuses both.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import click

from bpb_core.errors import BadInput

F = TypeVar("F", bound=Callable[..., Any])


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
