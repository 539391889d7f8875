"""Option types of the command line that click lacks: ranges of finite numbers.

``click.FloatRange`` lets ``nan`` through every bound (each comparison with it is false) and
``inf`` through any lower one, so ``--timeout nan`` or ``--rpm inf`` would reach the runner.
"""

from __future__ import annotations

import math
from typing import Any

import click


class FiniteFloat(click.FloatRange):
    """A :class:`click.FloatRange` that also refuses ``nan`` and infinities."""

    name = "finite number"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


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
