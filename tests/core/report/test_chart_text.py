"""Every text of a chart drawn through ``charts.png`` comes out as written: matplotlib reads text
between two ``$`` as TeX math, which italicised ``$x$`` and stopped the report on an invalid
formula. Plugins draw their own texts, so the figure's texts are made literal when it is saved;
the numbers tick formatters write with math on purpose (log axes) are left alone, and so is the
calling program's matplotlib."""

from __future__ import annotations

import io
from collections.abc import Callable
from typing import Any

import pytest

from bpb_core.report.charts import figure, png

TITLE, LEGEND, TICK, NOTE = "a$b$c plugin", "run $x$", "price $\\frac{$", "$y$ = 1"


def _chart(escape: Callable[[str], str]) -> Any:
    """A chart as a plugin draws it: its own title, legend label, tick names and text."""
    fig, axes = figure(1, 1, (5.0, 3.0))
    ax = axes[0, 0]
    ax.barh([0, 1], [30, 60], label=escape(LEGEND))
    ax.set_yticks([0, 1], [escape(TICK), escape("plain")])
    ax.set_title(escape(TITLE))
    ax.text(5, 0.5, escape(NOTE))
    fig.legend(loc="outside lower center")
    return fig


def _saved(fig: Any) -> bytes:
    """``fig`` saved by matplotlib itself, without ``png``."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()


def test_a_plugins_dollar_texts_are_drawn_as_written() -> None:
    drawn = png(_chart(lambda text: text))
    # matplotlib draws "\$" as a plain "$": the chart as it must look
    assert drawn == _saved(_chart(lambda text: text.replace("$", r"\$")))
    math = _chart(lambda text: text.replace(TICK, "plain"))  # TICK is no valid formula
    assert drawn != _saved(math)


def test_numbers_a_log_axis_writes_with_math_are_left_alone() -> None:
    def chart() -> Any:
        fig, axes = figure(1, 1, (5.0, 3.0))
        ax = axes[0, 0]
        ax.plot([1e-3, 1.0], [1e-15, 1.0])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title("plain")
        return fig

    assert png(chart()) == _saved(chart())


def test_the_callers_rcparams_are_left_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    import matplotlib

    monkeypatch.setitem(matplotlib.rcParams, "text.parse_math", True)
    before = dict(matplotlib.rcParams)
    png(_chart(lambda text: text))
    assert dict(matplotlib.rcParams) == before
