"""One self-contained HTML page, rendered with jinja2 (autoescaped): inline CSS, charts and
gallery images as base64 data URIs.

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

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0;color:#1d2433;
background:#f6f7f9}
main{max-width:1280px;margin:0 auto;padding:24px 32px 64px}
h1{font-size:26px;margin:8px 0 4px}h2{margin-top:40px;border-bottom:2px solid #dde1e7;
padding-bottom:4px}h3{margin:20px 0 6px}
.muted{color:#667085;font-size:13px}.warn{color:#8a4b00;background:#fff4e0;padding:6px 10px;
border-left:4px solid #e69f00;font-size:13px}
table{border-collapse:collapse;margin:8px 0 16px;font-size:13px;background:#fff}
th,td{border:1px solid #dde1e7;padding:4px 7px;text-align:right;white-space:nowrap}
th{background:#eef1f5;white-space:normal;max-width:9em;overflow-wrap:anywhere}
td:first-child,th:first-child{text-align:left;white-space:normal;min-width:10em}
tr.baseline td{color:#555;font-style:italic;background:#fafafa}
td.partial sup{color:#b45f06;font-size:10px;margin-left:2px}
td.short{color:#9aa0a6;background:repeating-linear-gradient(45deg,#f3f3f3 0 4px,#fff 4px 8px)}
.badge{display:inline-block;font-size:11px;padding:0 6px;border-radius:8px;background:#888;
color:#fff;margin-left:6px;font-style:normal}
img.chart{max-width:100%;background:#fff;border:1px solid #dde1e7;margin:8px 0}
.gallery{display:grid;grid-template-columns:repeat(auto-fill,minmax(560px,1fr));gap:16px}
.case{background:#fff;border:1px solid #dde1e7;border-radius:6px;padding:10px}
.case img{width:100%;display:block}.case ul{margin:4px 0;padding-left:18px;font-size:13px}
.scroll{overflow-x:auto;max-width:100%}.key{font-size:13px}.key span{font-weight:600}
"""
SCRIPT = """
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var ok = imgs.every(function (i) { return i.complete && i.naturalWidth > 0; });
  document.body.setAttribute('data-images', String(imgs.length));
  document.body.setAttribute('data-images-ok', ok ? 'yes' : 'no');
});
"""

TABLE = """{% if not rows %}<p class="muted">{{ empty }}</p>{% else %}<div class="scroll"><table>
<thead><tr>{% for h in head %}<th>{{ h }}</th>{% endfor %}</tr></thead><tbody>
{% for row in rows %}<tr{% if row.baseline %} class="baseline"{% endif %}>
{%- for c in row.cells %}<td{% if c.css %} class="{{ c.css }}"{% endif %}
{%- if c.title %} title="{{ c.title }}"{% endif %}>{{ c.text }}
{%- if c.note %}<sup>{{ c.note }}</sup>{% endif %}
{%- if loop.first and row.baseline %}<span class="badge">baseline</span>{% endif %}</td>
{%- endfor %}</tr>
{% endfor %}</tbody></table></div>{% endif %}"""

PAGE = """<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">
<title>{{ title }}</title><style>{{ css }}</style></head><body><main>
<h1>{{ title }}</h1><div class="muted">generated {{ when }} by bpb</div>
{% if parts|length > 1 %}<p class="warn">These runs answered {{ parts|length }} different
datasets. Each dataset has its own section below; runs on different datasets are never ranked
together.</p>{% endif %}
{% for part in parts %}
{% if parts|length > 1 %}<h2>Dataset {{ part.name }}</h2>{% endif %}
<h2>Runs</h2><ul>{% for run in part.runs %}<li><b>{{ run.label }}</b> &mdash; adapter
<code>{{ run.adapter }}</code>, model <code>{{ run.model }}</code>, tasks {{ run.tasks }},
{{ run.scenes }} scenes, dataset <code>{{ run.dataset }}</code>{% if run.hash %}, hash
<code>{{ run.hash }}</code>{% endif %}{% if run.baseline %} (baseline){% endif %}</li>
{% endfor %}</ul>
{% for heading, body in part.headline %}<h2>{{ heading }}</h2>{{ body }}{% endfor %}
<h2>Charts</h2>{% for name, uri in part.charts %}<h3>{{ name }}</h3>
<img class="chart" alt="{{ name }}" src="{{ uri }}">{% if part.chart_notes.get(name) %}
<p class="muted">{{ part.chart_notes[name] }}</p>{% endif %}{% endfor %}
{% for heading, body in part.sections %}<h2>{{ heading }}</h2>{{ body }}{% endfor %}
{% endfor %}
<h2>Failure gallery</h2><p class="muted">The worst answered scenes (lowest score), models before
baselines; the legend above each picture explains its marks.</p>
<div class="gallery">{% for case in cases %}<div class="case"><h3>{{ case.run }} &middot;
{{ case.scene_id }}</h3><div class="muted">horizon {{ case.horizon }} s &middot;
{{ case.scores }}</div>{% if case.uri %}<img alt="{{ case.scene_id }}" src="{{ case.uri }}">
{% endif %}{% for title, items in case.wrong %}<div class="key"><span>{{ title }}:</span>
{% if items %}<ul>{% for i in items %}<li>{{ i }}</li>{% endfor %}</ul>{% else %} all right
{% endif %}</div>{% endfor %}</div>{% else %}<p class="muted">{% if answered %}every one of the
{{ answered }} fully answered scenes scored 100%: nothing to show{% else %}no fully answered
scenes{% endif %}</p>
{% endfor %}</div><script>{{ script }}</script></main></body></html>"""


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

    return jinja2.Environment(autoescape=True, undefined=jinja2.StrictUndefined)


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
    template = _environment().from_string(TABLE)
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
        (
            bool(record.get("baseline", False)),
            [plain(record[c], c in percent) for c in columns],
        )
        for record in frame.to_dict(orient="records")
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
    template = _environment().from_string(PAGE)
    return template.render(
        title=title,
        when=datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        css=Markup(CSS),
        script=Markup(SCRIPT),
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
