"""One self-contained HTML page, rendered with jinja2 (autoescaped) from ``templates/``: inline
CSS, charts and gallery images as base64 data URIs.

The page loads nothing from anywhere (no fonts, scripts or styles from the network), so it works
offline and can be mailed around as one file. A small inline script marks ``<body>`` with
``data-images-ok="yes"`` once every image has decoded, which the tests read from headless
Chromium.
"""

from __future__ import annotations

import base64
import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from functools import cache
from typing import TYPE_CHECKING, Any

import pandas as pd
from markupsafe import Markup

from bpb_core.report.gallery import Case

if TYPE_CHECKING:
    import jinja2


@dataclass(frozen=True)
class Cell:
    """One table cell: its text, a small note after it (``<sup>``), a CSS class and a
    tooltip."""

    text: str
    note: str = ""
    css: str = ""
    title: str = ""


@cache
def _environment() -> jinja2.Environment:
    import jinja2

    loader = jinja2.PackageLoader("bpb_core.report", "templates")
    return jinja2.Environment(loader=loader, autoescape=True, undefined=jinja2.StrictUndefined)


def data_uri(png: bytes) -> str:
    """``data:image/png;base64,...`` for ``png``."""
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def plain(value: object, percent: bool) -> Cell:
    """A cell of a plain value: NaN as a dash, floats as percentages or 4 digits."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return Cell("–")
    if isinstance(value, bool):
        return Cell("yes" if value else "no")
    if isinstance(value, float):
        return Cell(f"{100 * value:.1f}%" if percent else f"{value:.4g}")
    return Cell(str(value))


def cells(head: Sequence[str], rows: Sequence[tuple[bool, Sequence[Cell]]], empty: str) -> Markup:
    """An HTML table of ready cells; ``rows`` are (baseline, cells) pairs."""
    items = [{"baseline": baseline, "cells": list(row)} for baseline, row in rows]
    template = _environment().get_template("table.html")
    return Markup(template.render(head=list(head), rows=items, empty=empty))


def table(
    frame: pd.DataFrame,
    *,
    percent: Collection[str] = (),
    drop: Sequence[str] = ("adapter", "model"),
    empty: str = "nothing to show",
    headers: dict[str, str] | None = None,
) -> Markup:
    """An HTML table of ``frame``: ``percent`` columns as percentages, baseline rows greyed and
    marked; ``headers`` renames columns for display."""
    columns = [c for c in frame.columns if c not in drop and c != "baseline"]
    rows = [
        (bool(row.get("baseline", False)), [plain(row[c], c in percent) for c in columns])
        for row in frame.to_dict(orient="records")
    ]
    names = headers or {}
    return cells([names.get(str(c), str(c)) for c in columns], rows, empty)


def render(
    *,
    title: str,
    parts: Sequence[dict[str, Any]],
    cases: Sequence[Case],
    answered: int = 0,
    titles: Mapping[str, str] | None = None,
) -> str:
    """The whole page: per dataset its runs, headline sections, charts and sections, then the
    failure gallery.

    Each part is a dict with ``name``, ``runs`` (dicts), ``headline`` and ``sections``
    ((heading, HTML body) pairs), ``charts`` ({title: PNG bytes}) and ``chart_notes``
    ({title: a line shown under the chart}). ``titles`` names the tasks in the gallery (a task
    without one keeps its name).
    """
    shown = [{**p, "charts": [(k, data_uri(v)) for k, v in p["charts"].items()]} for p in parts]
    template = _environment().get_template("report.html")
    return template.render(
        title=title,
        when=datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        parts=shown,
        cases=[_case(c, titles or {}) for c in cases],
        answered=answered,
    )


def _case(case: Case, titles: Mapping[str, str]) -> dict[str, Any]:
    scores = ", ".join(f"{k} {100 * v:.0f}%" for k, v in case.scores.items() if not math.isnan(v))
    named = [(titles.get(task) or task, items) for task, items in case.wrong.items()]
    wrong = [(f"{name} wrong" if items else name, items) for name, items in named]  # or all right
    uri = data_uri(case.png) if case.png else ""
    return {"run": case.run, "scene_id": case.scene_id, "horizon": f"{case.horizon:g}"} | {
        "scores": scores,
        "uri": uri,
        "wrong": wrong,
    }
