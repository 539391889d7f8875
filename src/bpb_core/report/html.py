"""One self-contained HTML page: inline CSS, charts and gallery images as base64 data URIs.

The page loads nothing from anywhere (no fonts, scripts or styles from the network), so it works
offline and can be mailed around as one file. A small inline script marks ``<body>`` with
``data-images-ok="yes"`` once every image has decoded, which the tests read from headless
Chromium.
"""

from __future__ import annotations

import base64
import html
import math
from collections.abc import Collection, Sequence
from datetime import UTC, datetime

import pandas as pd

from bpb_core.report.gallery import Case
from bpb_core.results.reading import RunFolder

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0;color:#1d2433;
background:#f6f7f9}
main{max-width:1280px;margin:0 auto;padding:24px 32px 64px}
h1{font-size:26px;margin:8px 0 4px}h2{margin-top:40px;border-bottom:2px solid #dde1e7;
padding-bottom:4px}h3{margin:20px 0 6px}
.muted{color:#667085;font-size:13px}
table{border-collapse:collapse;margin:8px 0 16px;font-size:13px;background:#fff}
th,td{border:1px solid #dde1e7;padding:4px 8px;text-align:right}
th{background:#eef1f5}td:first-child,th:first-child{text-align:left}
tr.baseline td{color:#555;font-style:italic;background:#fafafa}
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


def data_uri(png: bytes) -> str:
    """``data:image/png;base64,...`` for ``png``."""
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _cell(column: str, value: object, percent: bool) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "<td>&ndash;</td>"
    if isinstance(value, bool):
        return f"<td>{'yes' if value else 'no'}</td>"
    if isinstance(value, float):
        text = f"{100 * value:.1f}%" if percent else f"{value:.4g}"
        return f"<td>{text}</td>"
    return f"<td>{html.escape(str(value))}</td>"


def table(
    frame: pd.DataFrame,
    *,
    percent: Collection[str] = (),
    drop: Sequence[str] = ("adapter", "model"),
    empty: str = "nothing to show",
) -> str:
    """An HTML table of ``frame``: ``percent`` columns as percentages, baseline rows greyed and
    marked."""
    if frame.empty:
        return f'<p class="muted">{html.escape(empty)}</p>'
    columns = [c for c in frame.columns if c not in drop and c != "baseline"]
    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in columns)
    rows = []
    for record in frame.to_dict(orient="records"):
        baseline = bool(record.get("baseline", False))
        cells = []
        for column in columns:
            cell = _cell(str(column), record[column], column in percent)
            if column == "run" and baseline:
                cell = cell.replace("</td>", '<span class="badge">baseline</span></td>')
            cells.append(cell)
        css = ' class="baseline"' if baseline else ""
        rows.append(f"<tr{css}>{''.join(cells)}</tr>")
    body = "".join(rows)
    inner = f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"
    return f"<div class='scroll'>{inner}</div>"


def _runs_section(runs: Sequence[RunFolder]) -> str:
    items = []
    for run in runs:
        info = run.manifest
        items.append(
            f"<li><b>{html.escape(run.label)}</b> &mdash; adapter <code>"
            f"{html.escape(run.adapter)}</code>, model <code>{html.escape(run.model)}</code>, "
            f"tasks {html.escape(', '.join(run.tasks))}, {len(run.scene_keys)} scenes, "
            f"dataset <code>{html.escape(str(run.dataset))}</code>"
            f"{_hash(info)}{'' if not run.baseline else ' (baseline)'}</li>"
        )
    return "<ul>" + "".join(items) + "</ul>"


def _hash(info: dict[str, object]) -> str:
    value = info.get("dataset_hash")
    return f", hash <code>{html.escape(str(value)[:12])}</code>" if value else ""


def _case(case: Case) -> str:
    scores = ", ".join(f"{k} {100 * v:.0f}%" for k, v in case.scores.items() if not math.isnan(v))

    def listing(title: str, items: list[str]) -> str:
        if not items:
            return f"<div class='key'><span>{html.escape(title)}:</span> all right</div>"
        body = "".join(f"<li>{html.escape(i)}</li>" for i in items)
        return f"<div class='key'><span>{html.escape(title)}:</span><ul>{body}</ul></div>"

    image = (
        f"<img alt='{html.escape(case.scene_id)}' src='{data_uri(case.png)}'>" if case.png else ""
    )
    wrong = "".join(listing(f"{task.upper()} wrong", items) for task, items in case.wrong.items())
    return (
        f"<div class='case'><h3>{html.escape(case.run)} &middot; {html.escape(case.scene_id)}"
        f"</h3><div class='muted'>horizon {case.horizon:g} s &middot; {scores}</div>"
        f"{image}{wrong}</div>"
    )


def render(
    *,
    title: str,
    runs: Sequence[RunFolder],
    headline: Sequence[tuple[str, str]],
    sections: Sequence[tuple[str, str]],
    charts: dict[str, bytes],
    cases: Sequence[Case],
) -> str:
    """The whole page: runs, ``headline`` sections, charts, ``sections``, failure gallery.

    Sections are (heading, HTML body) pairs.
    """
    when = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    chart_html = "".join(
        f"<h3>{html.escape(name)}</h3><img class='chart' alt='{html.escape(name)}' "
        f"src='{data_uri(png)}'>"
        for name, png in charts.items()
    )

    def join(parts: Sequence[tuple[str, str]]) -> str:
        return "".join(f"<h2>{html.escape(h)}</h2>{content}" for h, content in parts)

    gallery = "".join(_case(c) for c in cases) or "<p class='muted'>no answered scenes</p>"
    return (
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
        f"<title>{html.escape(title)}</title><style>{CSS}</style></head><body><main>"
        f"<h1>{html.escape(title)}</h1><div class='muted'>generated {when} by bpb</div>"
        f"<h2>Runs</h2>{_runs_section(runs)}"
        f"{join(headline)}<h2>Charts</h2>{chart_html}{join(sections)}"
        "<h2>Failure gallery</h2><p class='muted'>The worst answered scenes (lowest score), "
        "models before baselines; the legend above each picture explains its marks.</p>"
        f"<div class='gallery'>{gallery}</div>"
        f"<script>{SCRIPT}</script></main></body></html>"
    )
