"""How one report part is shown: the HTML sections (the headline, answered-only first; accuracy
by horizon with every cell's completeness; the other tables), the self-contained page, the
exports (every table as CSV, the paper's tables, the headline leaderboard and accuracy by
horizon, both answered only, as Markdown and LaTeX booktabs) and the JSON summary of ``bpb
report --json``.

A cell under 100% answered carries its completeness as a note (in brackets in Markdown and
LaTeX); a cell under the threshold is greyed and reads "left out", so no table states a finding
that comes from missing data.

The page is rendered with jinja2 (autoescaped) from ``templates/``: inline CSS, charts and
gallery images as base64 data URIs. It loads nothing from anywhere (no fonts, scripts or styles
from the network), so it works offline and can be mailed around as one file. A small inline
script marks ``<body>`` with ``data-images-ok="yes"`` once every image has decoded, which the
tests read from headless Chromium.

The failure gallery (:func:`build_cases`) shows the worst answered scenes, with truth and
prediction drawn on the scene: per run, the answered scenes with the lowest score (weighted by
the first suite whose tasks the scene was asked, else the mean over its tasks). What is shown
comes from the plugins: the scene family draws the scene
(:class:`~bpb_core.capabilities.Picturing`), each task's scorer marks truth and prediction on it
(:class:`~bpb_core.capabilities.DrawsOverlay`) and says in words what was wrong
(:class:`~bpb_core.capabilities.ExplainsErrors`). Core only chooses the scenes and lays them
out.
"""

from __future__ import annotations

import base64
import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from markupsafe import Markup

from bpb_core.capabilities import DrawsOverlay, ExplainsErrors, Picturing
from bpb_core.errors import blamed, writing
from bpb_core.layout import SceneKey
from bpb_core.picture import ScenePicture
from bpb_core.plugin_calls import returned
from bpb_core.results.tables import (
    incomplete_lines,
    level,
    metadata_by_horizon,
    unanswered_lines,
    unparsed_lines,
    warning_lines,
    worst_cells,
)
from bpb_core.run_folder import REPLIED
from bpb_core.scored_units import object_origin

if TYPE_CHECKING:
    import jinja2

    from bpb_core.interfaces import Scorer
    from bpb_core.report.build import Completeness, ReportPart
    from bpb_core.results.frames import Results
    from bpb_core.results.reading import RunFolder


SCORE = "score"


@dataclass(frozen=True)
class Case:
    """One gallery entry: which run and scene, its scores, what was wrong per task, the image."""

    run: str
    scene_id: str
    horizon: float
    scores: dict[str, float]
    wrong: dict[str, list[str]] = field(default_factory=dict)
    png: bytes = b""


def worst_cases(results: Results, count: int = 8) -> pd.DataFrame:
    """Up to ``count`` answered (run, scene) pairs with the lowest score.

    Runs take turns (models before baselines, each run's worst scene first), so one bad run
    does not fill the gallery; only scenes answered in every task and not fully right qualify.
    Equal scores keep scene order (horizon, then index).
    """
    wide = scene_totals(results)
    # ties in scene order, (horizon, index): the id's numbers as numbers (h3_9999 before
    # h3_10000, h3 before h10), not the id's text
    wide = wide[wide[SCORE] < 1.0].sort_values([SCORE, "horizon", "index"], kind="stable")
    wide["turn"] = wide.groupby("run", observed=True).cumcount()
    ranked = wide.sort_values(["turn", "baseline", SCORE, "run"], kind="stable")
    return ranked.head(count).drop(columns="turn").reset_index(drop=True)


def scene_totals(results: Results) -> pd.DataFrame:
    """One row per fully answered (run, scene): each task's score and ``score``, the weighted
    score of the first suite whose tasks the scene was asked (else the mean over its tasks)."""
    scenes, suites = results.scenes, results.suites
    wide = scenes.pivot_table(
        index=["run", "baseline", "horizon", "index", "scene_id"],
        columns="task",
        values="score",
        observed=True,
    )
    wide.columns.name = None
    answered = scenes.assign(ok=scenes["status"].isin(REPLIED))
    all_ok = answered.groupby(["run", "horizon", "index"], observed=True)["ok"].all()
    wide = wide.reset_index()
    keys = pd.MultiIndex.from_frame(wide[["run", "horizon", "index"]])
    wide = wide[all_ok.reindex(keys).fillna(False).to_numpy(dtype=bool)].copy()
    tasks = sorted(str(t) for t in scenes["task"].unique())
    score = pd.Series(float("nan"), index=wide.index)
    for suite in suites:
        if not set(suite.weights) <= set(wide.columns):
            continue
        asked = wide[list(suite.weights)].notna().all(axis=1) & score.isna()
        weighted = sum(w * wide[t] for t, w in suite.weights.items())
        score = score.where(~asked, weighted)
    mean = wide[[t for t in tasks if t in wide.columns]].mean(axis=1)
    wide[SCORE] = score.fillna(mean)
    return wide


def build_cases(
    results: Results,
    scorers: Mapping[str, Scorer],
    count: int = 8,
    origins: Mapping[str, str] | None = None,
) -> list[Case]:
    """Gallery cases for the worst scenes of ``results``, drawn and explained by the plugins.

    Args:
        origins: Who supplied each task's scorer (``Registered.origin``), for one-line errors.

    Raises:
        PluginBug: A scorer's ``explain`` or ``overlay`` raised or returned the wrong type.
    """
    runs = {run.label: run for run in results.runs}
    units = results.units
    cases = []
    for row in worst_cases(results, count).to_dict(orient="records"):
        run, sid = runs[str(row["run"])], str(row["scene_id"])
        rows = units[(units["run"] == run.label) & (units["scene_id"] == sid)]
        key = SceneKey(float(row["horizon"]), int(row["index"]))
        tasks = [t for t in results.tasks if t in row and not pd.isna(row[t])]
        scores = {t: float(row[t]) for t in tasks} | {SCORE: float(row[SCORE])}
        by_task = {t: rows[rows["task"] == t] for t in tasks}
        wrong = {
            t: _explain(scorer, _origin(origins, t), by_task[t]) for t in tasks
            if isinstance(scorer := scorers[t], ExplainsErrors)
        }  # fmt: skip
        png = drawing(run, key, by_task, scorers, origins)
        cases.append(Case(run.label, sid, key.horizon, scores, wrong, png))
    return cases


def drawing(
    run: RunFolder,
    key: SceneKey,
    rows: Mapping[str, pd.DataFrame],
    scorers: Mapping[str, Scorer],
    origins: Mapping[str, str] | None = None,
) -> bytes:
    """The family's picture of the scene with every task's overlay; empty when the family
    draws nothing.

    Raises:
        PluginBug: A scorer's ``overlay`` raised, naming who supplied it (``origins``).
    """
    if not isinstance(run.family, Picturing):
        return b""
    scene, _ = run.truth(key)
    picture = _picture(run.family, run, key, scene)
    for task, task_rows in rows.items():
        scorer = scorers[task]
        if isinstance(scorer, DrawsOverlay):
            with blamed(_origin(origins, task), f"scorer {_name(scorer)!r}: overlay()"):
                scorer.overlay(picture, task_rows)
    return picture.png()


def _picture(family: Picturing, run: RunFolder, key: SceneKey, scene: Any) -> ScenePicture:
    """The run's family's ``picture``, checked: a :class:`~bpb_core.picture.ScenePicture`."""
    origin = run.family_origin or object_origin(family)
    what = f"scene family {_name(family)!r}: picture()"
    with blamed(origin, what):
        picture = family.picture(run.dataset, key.dir(run.dataset), scene)
    if isinstance(picture, ScenePicture):
        return picture
    raise returned(origin, what, type(picture).__name__, "bpb_core.ScenePicture")


def _origin(origins: Mapping[str, str] | None, task: str) -> str:
    return (origins or {}).get(task, f"the scorer of task {task!r}")


def _name(scorer: object) -> str:
    return str(getattr(scorer, "name", type(scorer).__name__))


def _explain(scorer: ExplainsErrors, origin: str, rows: pd.DataFrame) -> list[str]:
    """``scorer.explain(rows)``, checked: a list of strings."""
    what = f"scorer {_name(scorer)!r}: explain()"
    with blamed(origin, what):
        lines = scorer.explain(rows)
    if isinstance(lines, list | tuple) and all(isinstance(line, str) for line in lines):
        return list(lines)
    shown = repr(lines)
    raise returned(origin, what, shown if len(shown) <= 80 else shown[:77] + "...", "a list of str")


def paper_tables(part: ReportPart, rule: Completeness) -> dict[str, pd.DataFrame]:
    """The headline leaderboard, accuracy by horizon (answered only) and each task's metrics
    table as frames of text."""
    out = {
        "leaderboard": _frame(*headline_cells(part, rule)),
        "by_horizon": _frame(*horizon_cells(part.tables["accuracy_answered"], rule)),
    }
    for task, notes in part.metric_notes.items():
        table = part.tables[f"{task}_metrics"]
        columns = ["complete", *notes]
        rows: Rows = [
            (
                bool(row["baseline"]),
                [Cell(str(row["run"])), *(plain(row[c], True) for c in columns)],
            )
            for row in table.to_dict(orient="records")
        ]
        out[f"{task}_metrics"] = _frame(["run", *columns], rows)
    return out


def _frame(head: list[str], rows: Rows) -> pd.DataFrame:
    data = []
    for baseline, cells in rows:
        texts = [f"{c.text} ({c.note})" if c.note else c.text for c in cells]
        texts[0] += " (baseline)" if baseline else ""
        data.append(texts)
    return pd.DataFrame(data, columns=head, dtype="str")


def markdown(frame: pd.DataFrame) -> str:
    """A GitHub-flavoured Markdown table (first column left-aligned, the others right)."""

    def line(cells: list[str]) -> str:
        return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"

    align = [":---", *["---:"] * (len(frame.columns) - 1)]
    rows = [line([str(c) for c in frame.columns]), line(align)]
    rows += [line([str(v) for v in row]) for row in frame.itertuples(index=False)]
    return "\n".join(rows) + "\n"


def latex(frame: pd.DataFrame, caption: str) -> str:
    """A booktabs LaTeX table (``\\toprule``/``\\midrule``/``\\bottomrule``), text escaped."""
    styler = frame.style.hide(axis="index").format(escape="latex")
    styler = styler.format_index(escape="latex", axis=1)
    align = "l" + "r" * (len(frame.columns) - 1)
    caption = caption.replace("%", "\\%")
    return styler.to_latex(
        hrules=True, column_format=align, caption=caption, position="t", position_float="centering"
    )


def write_exports(part: ReportPart, out: Path, prefix: str, rule: Completeness) -> dict[str, Path]:
    """Every table as CSV under ``out/tables``, the paper's tables also as ``.md`` and
    ``.tex``."""
    files: dict[str, Path] = {}
    for name, frame in part.tables.items():
        path = out / "tables" / f"{prefix}{name}.csv"
        with writing(path):
            frame.to_csv(path, index=False)
        files[f"table:{prefix}{name}"] = path
    captions = {
        "leaderboard": "Leaderboard: mean accuracy over horizons, answered only (strict beside).",
        "by_horizon": "Accuracy by horizon, answered only (in brackets: the share answered).",
    }
    for name, frame in paper_tables(part, rule).items():
        captions.setdefault(name, f"{name.replace('_', ' ')}, answered only.")
        md = out / "tables" / f"{prefix}{name}.md"
        with writing(md):
            md.write_text(markdown(frame), encoding="utf-8")
        tex = out / "tables" / f"{prefix}{name}.tex"
        with writing(tex):
            tex.write_text(latex(frame, captions[name]), encoding="utf-8")
        files[f"markdown:{prefix}{name}"], files[f"latex:{prefix}{name}"] = md, tex
    return files


def records(frame: pd.DataFrame) -> list[dict[str, Any]]:
    """A frame as JSON-ready dicts (NaN as ``None``, numpy scalars as Python ones)."""
    cleaned = frame.astype(object).where(frame.notna(), None)
    out = []
    for row in cleaned.to_dict(orient="records"):
        out.append({str(k): v.item() if isinstance(v, np.generic) else v for k, v in row.items()})
    return out


def part_json(part: ReportPart) -> dict[str, Any]:
    """The JSON summary of one part (one dataset)."""
    tables, results = part.tables, part.results
    cells = ["run", "task", "horizon", "answered", "expected", "completeness", "level", "epochs"]
    by_horizon = tables["accuracy"].merge(
        tables["accuracy_answered"][["run", "task", "horizon", "accuracy", "scenes"]],
        on=["run", "task", "horizon"], suffixes=("_strict", "_answered"),
    )  # fmt: skip
    return {
        "dataset": part.dataset,
        "dataset_path": part.path,
        "scenes": part.scenes or None,
        "leaderboard": records(tables["summary"]),
        "leaderboard_answered": records(tables["leaderboard_answered"]),
        "suites": {s.name: dict(s.weights) for s in results.suites},
        "bootstrap": records(tables["bootstrap"]),
        "bootstrap_answered": records(tables["bootstrap_answered"]),
        "stable": records(tables["leaderboard_stable"]),
        "stable_exclusions": records(tables["stable_exclusions"]),
        "by_horizon": records(by_horizon),
        "completeness": records(tables["accuracy"][cells]),
        "incomplete": incomplete_lines(results),
        "unanswered": unanswered_lines(results),
        "unparsed": unparsed_lines(results),
        "different_scenes": different_scenes_note(part),
        "different_conditions": different_conditions_note(part),
        "usage": records(tables["usage"]),
        "pairs": records(tables["pairs"]),
        "references": records(tables["references"]),
        "metrics": {t: records(tables[f"{t}_metrics"]) for t in part.metric_notes},
        "metric_notes": {t: dict(notes) for t, notes in part.metric_notes.items()},
        "diagnostics": {d.name: records(tables[d.name]) for d in part.diagnostics},
    }


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


def html_cells(
    head: Sequence[str], rows: Sequence[tuple[bool, Sequence[Cell]]], empty: str
) -> Markup:
    """An HTML table of ready cells; ``rows`` are (baseline, cells) pairs."""
    items = [{"baseline": baseline, "cells": list(row)} for baseline, row in rows]
    template = _environment().get_template("table.html")
    return Markup(template.render(head=list(head), rows=items, empty=empty))


def html_table(
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
    return html_cells([names.get(str(c), str(c)) for c in columns], rows, empty)


def render_page(
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


LEFT_OUT = "left out"


def pct(value: float) -> str:
    """A share as a percentage with one decimal."""
    return f"{100 * value:.1f}%"


def completeness_cell(value: float, rule: Completeness) -> Cell:
    """A completeness share, marked partial or short."""
    grade = level(value, rule.min_complete)
    css = "" if grade == "full" else grade
    return Cell(pct(value), css=css, title="share of the scene-task calls answered")


def score_cell(value: float, worst: float, rule: Completeness) -> Cell:
    """A leaderboard score with its least complete cell ``worst``: "left out" and greyed when
    that is under the threshold (and the score blank), marked with it when under 100%; "–"
    when there is no cell (``worst`` NaN: the run was not asked the task)."""
    if math.isnan(worst):  # no cell at all: the run was not asked this task
        return Cell("–", title="not asked by this run")
    grade = level(worst, rule.min_complete)
    if grade == "short" and math.isnan(value):
        return Cell(LEFT_OUT, css="short", title=f"a horizon is under {pct(rule.min_complete)}")
    if math.isnan(value):
        return Cell("–")
    if grade == "full":
        return Cell(pct(value))
    return Cell(pct(value), note=pct(worst), css=grade, title="least complete horizon answered")


Rows = list[tuple[bool, list[Cell]]]


def headline(part: ReportPart, rule: Completeness) -> list[tuple[str, Markup]]:
    """The leaderboard leading with the answered-only scores and completeness, the strict score
    beside, and what is incomplete."""
    head, rows = headline_cells(part, rule)
    body = _headline_note(part, rule) + html_cells(head, rows, "no runs")
    out = [("Leaderboard (answered only; strict beside)", body + incomplete_notes(part))]
    if not part.tables["references"].empty:
        sources = Markup("").join(
            Markup("<p class='muted'>{}</p>").format(line) for line in reference_sources(part)
        )
        note = Markup("<p class='muted'>{}</p>").format(REFERENCE_NOTE)
        body = note + html_cells(*reference_cells(part), "no figures") + sources
        out.append(("Published figures beside your runs", body))
    for task in part.metric_notes:
        out.append((f"{task} metrics beside accuracy (answered only)", metrics_body(part, task)))
    return out


def metrics_body(part: ReportPart, task: str) -> Markup:
    """A task's metrics table (from its scorer) with what each metric says."""
    notes = part.metric_notes[task]
    items = Markup("").join(
        Markup("<li><b>{}</b>: {}</li>").format(name, note) for name, note in notes.items()
    )
    table = part.tables[f"{task}_metrics"]
    percent = (*notes, "complete")
    listed = Markup("<ul class='muted'>{}</ul>").format(items)
    return html_table(table, percent=percent, drop=_dropped(table)) + listed


def headline_cells(part: ReportPart, rule: Completeness) -> tuple[list[str], Rows]:
    """The headline leaderboard's header and (baseline, cells) rows, best first."""
    tables, suites = part.tables, part.results.suites
    board, strict = tables["leaderboard_answered"], tables["leaderboard"].set_index("run")
    tasks = part.results.tasks
    first = suites[0].name if suites else None
    ci = tables["bootstrap_answered"]
    head = ["run", "complete", *tasks, *(s.name for s in suites)]
    head += [f"{first} strict", f"{first} 95% CI"] if first else []
    head += ["worst cell", "left out"]
    worst = worst_cells(tables["accuracy"])
    rows = []
    for row in board.to_dict(orient="records"):
        run, short = str(row["run"]), str(row["short"])
        found = worst.loc[run].to_dict() if run in worst.index else {}
        least = {t: float(found.get(t, 1.0)) for t in tasks}
        # a suite's least complete cell; NaN when a task of it was not asked
        of = {s.name: float(np.min([least.get(t, 1.0) for t in s.weights])) for s in suites}
        cells = [Cell(run), completeness_cell(float(row["completeness"]), rule)]
        cells += [score_cell(float(row[m]), least[m], rule) for m in tasks]
        cells += [score_cell(float(row[s.name]), of[s.name], rule) for s in suites]
        if first:
            strict_score = float(strict.loc[run, first])  # type: ignore[arg-type]
            cells.append(score_cell(strict_score, of[first], rule))
            cells.append(_interval(ci, run, first))
        cells += [completeness_cell(float(row["worst_cell"]), rule), Cell(short or "–")]
        rows.append((bool(row["baseline"]), cells))
    return head, rows


def _interval(ci: pd.DataFrame, run: str, metric: str) -> Cell:
    rows = ci[(ci["run"] == run) & (ci["metric"] == metric)]
    if rows.empty or rows["lo"].isna().all():
        return Cell("–")
    return Cell(f"{pct(float(rows['lo'].iloc[0]))}–{pct(float(rows['hi'].iloc[0]))}")


def reference_cells(part: ReportPart) -> tuple[list[str], Rows]:
    """Published figures beside the runs of their models: header and rows (the run's strict
    score with its 95% interval, the stated score, the difference in points)."""
    head = ["run", "figure", "yours (strict)", "95% CI", "stated", "diff", "where", "note"]
    rows: Rows = []
    for row in part.tables["references"].to_dict(orient="records"):
        horizon = float(row["horizon"])
        span = "mean" if math.isnan(horizon) else f"{horizon:g} s"
        shown = not math.isnan(float(row["estimate"]))
        yours = Cell(pct(float(row["estimate"]))) if shown else Cell("–")
        interval = f"{pct(float(row['lo']))}–{pct(float(row['hi']))}" if shown else "–"
        diff = f"{100 * float(row['diff']):+.1f} pt" if shown else "–"
        cells = [Cell(str(row["run"])), Cell(f"{row['metric']} {span}"), yours, Cell(interval)]
        stated = Cell(f"{100 * float(row['stated']):.2f}%")  # as the publication writes it
        cells += [stated, Cell(diff), Cell(str(row["where"]))]
        rows.append((False, [*cells, Cell(str(row["note"]) or "–", css="" if shown else "short")]))
    return head, rows


def reference_sources(part: ReportPart) -> list[str]:
    """The citation line of each reference the part's table shows figures of."""
    table = part.tables["references"].drop_duplicates("reference")
    pairs = zip(table["reference"], table["source"], strict=True)
    return [f"{name}: {source}" for name, source in pairs]


REFERENCE_NOTE = (
    "Scores a publication states for the models of these runs (only the figures it states in "
    "its text), beside each run's strict score on the same horizons: a stated score inside the "
    "run's interval is no disagreement."
)


def _headline_note(part: ReportPart, rule: Completeness) -> Markup:
    suites = ", ".join(f"{s.name} ({s.summary})" for s in part.results.suites)
    text = (
        "Mean accuracy over horizons. Answered only: calls that never returned an answer "
        "(API error, never sent) are left out; a parse error stays wrong. Strict (the paper): "
        "they are wrong too. complete: the share answered; worst cell: the least answered "
        f"(task, horizon). A task with a cell under {pct(rule.min_complete)} answered is "
        + ("kept but marked !" if rule.include_incomplete else "left out of the ranking")
        + ". Baselines are floors (stasis, straight, random) and the ceiling (oracle)."
        + (f" Suites: {suites}." if suites else "")
    )
    note = Markup("<p class='muted'>{}</p>").format(text)
    if not part.results.units["baseline"].any():
        note += Markup("<p class='warn'>{}</p>").format(
            "No baseline ran on this dataset, so the floors a score must beat are not shown: "
            f"bpb run --data {part.path} --adapter baseline:stasis --adapter baseline:straight "
            "(offline, free), then report again."
        )
    for different in (different_scenes_note(part), different_conditions_note(part)):
        if different:
            note += Markup("<p class='warn'>{}</p>").format(different)
    return note


def different_scenes_note(part: ReportPart) -> str | None:
    """The warning that the runs were asked different scenes of a task they share (so their
    scores are means over different scenes), or ``None``; shown in the terminal, JSON and HTML
    alike. The counts are of distinct scene-tasks (not calls: epochs ask the same scenes again);
    a task one run was not asked is its own '–'."""
    asked = part.results.units[["run", "task", "scene_id"]].drop_duplicates()
    asked = asked.astype(str)
    scenes = asked.groupby(["task", "run"])["scene_id"].agg(frozenset)
    if all(group.nunique() < 2 for _, group in scenes.groupby(level="task")):
        return None
    counts = sorted(set(asked.groupby("run").size().tolist()))
    if len(counts) > 1:
        told = f"different numbers of scenes ({', '.join(map(str, counts))} scene-tasks)"
    else:
        told = f"different scenes ({counts[0]} scene-tasks each, not the same ones)"
    return (
        f"The runs were asked {told}: their scores are means over different scenes; compare "
        "them in the paired comparisons."
    )


def different_conditions_note(part: ReportPart) -> str | None:
    """The warning that the runs were asked under different conditions (input mode, chain of
    thought per task, as their answer files record), so one leaderboard ranks different
    questions; ``None`` when they agree. Shown in the terminal, JSON and HTML alike."""
    calls = part.results.calls
    calls = calls[calls["status"] != "missing"]  # a call never made records no condition
    found = [_condition("input mode", calls, "input_mode", {})]
    for task, asked in calls.groupby("task", observed=True):
        found.append(_condition(f"chain of thought on {task}", asked, "cot", COT))
    found = [text for text in found if text]
    if not found:
        return None
    return (
        f"The runs were asked under different conditions ({'; '.join(found)}): a gap between "
        "them may come from the conditions, not the models; rank only runs asked alike."
    )


COT = {"True": "on", "False": "off"}


def _condition(name: str, calls: pd.DataFrame, column: str, words: dict[str, str]) -> str:
    """``name: image (a, b), state (c)`` when the runs' ``column`` differs, else ``""``."""
    by_run = calls.groupby("run", observed=True)[column].agg(
        lambda values: ", ".join(sorted({words.get(str(v), str(v)) for v in values.dropna()}))
    )
    runs: dict[str, list[str]] = {}
    for run, value in by_run.items():
        runs.setdefault(str(value) or "?", []).append(str(run))
    if len(runs) < 2:
        return ""
    return f"{name}: " + ", ".join(f"{v} ({', '.join(r)})" for v, r in sorted(runs.items()))


def incomplete_notes(part: ReportPart) -> Markup:
    """One warning line per run with calls that failed on infrastructure or were never sent,
    one per run with replies that held no answer (refused, cut, empty: per task), and one per
    run with tasks mostly answered in a form its parser could not read."""
    lines = [f"{run}: {text}" for run, text in warning_lines(part.results)]
    return Markup("").join(Markup("<p class='warn'>{}</p>").format(line) for line in lines)


def horizon_cells(acc: pd.DataFrame, rule: Completeness) -> tuple[list[str], Rows]:
    """The by-horizon table's header and (baseline, cells) rows, one row per (run, task):
    partial cells carry their completeness, short cells are greyed and left out of the mean."""
    horizons = sorted(float(h) for h in acc["horizon"].unique())
    head = ["run", "task", *(f"h{h:g}" for h in horizons), "mean"]
    rows = []
    for (run, task), frame in acc.groupby(["run", "task"], observed=True, sort=False):
        cells = [Cell(str(run)), Cell(str(task))]
        by_h = {float(r["horizon"]): dict(r) for r in frame.to_dict(orient="records")}
        values = []
        for h in horizons:
            if h not in by_h:
                cells.append(Cell("–"))
                continue
            cell = by_h[h]
            cells.append(_horizon_cell(cell, rule))
            short = cell["level"] == "short" and not rule.include_incomplete
            values.append(math.nan if short else float(cell["accuracy"]))
        mean = math.nan if any(math.isnan(v) for v in values) else sum(values) / len(values)
        cells.append(Cell(LEFT_OUT, css="short") if math.isnan(mean) else Cell(pct(mean)))
        rows.append((bool(frame["baseline"].iloc[0]), cells))
    return head, rows


def _answered_title(cell: Mapping[Any, Any]) -> str:
    """``6 of 8 answered``; with ``--epochs`` (answers, not scene-tasks, are counted)
    ``6 of 8 answers (4 scene-tasks x 2 epochs)``."""
    done, expected, epochs = int(cell["answered"]), int(cell["expected"]), int(cell["epochs"])
    if epochs == 1:
        return f"{done} of {expected} answered"
    return f"{done} of {expected} answers ({expected // epochs} scene-tasks x {epochs} epochs)"


def _horizon_cell(cell: Mapping[Any, Any], rule: Completeness) -> Cell:
    value, done = float(cell["accuracy"]), float(cell["completeness"])
    answered = _answered_title(cell)
    if cell["level"] == "short":
        text = pct(value) if rule.include_incomplete and not math.isnan(value) else LEFT_OUT
        return Cell(text, note=pct(done), css="short", title=answered)
    if math.isnan(value):
        return Cell("–", title=answered)
    if cell["level"] == "partial":
        return Cell(pct(value), note=pct(done), css="partial", title=answered)
    return Cell(pct(value), title=answered)


def sections(part: ReportPart, rule: Completeness) -> list[tuple[str, Markup]]:
    """The part's other sections: by horizon, stable subset, intervals, pairs, diagnostics,
    usage."""
    tables = part.tables
    pairs = tables["pairs"]
    scores = [*part.results.tasks, *(s.name for s in part.results.suites)]
    key = Markup(
        "<p class='muted'>A small number after a value is the share of the cell's scenes "
        "answered (under 100%); a greyed cell is under {} and left out.</p>"
    ).format(pct(rule.min_complete))
    out = [
        *(
            (f"Accuracy by horizon ({view})", key + html_cells(*cells, "no answers"))
            for view, cells in (
                ("answered only", horizon_cells(tables["accuracy_answered"], rule)),
                ("strict", horizon_cells(tables["accuracy"], rule)),
            )
        ),
        (
            "Leaderboard on stable scenes (strict)",
            html_table(
                tables["leaderboard_stable"],
                percent=[*scores, "completeness", "worst_cell"],
                drop=_dropped(tables["leaderboard_stable"]),
                empty="no stable scenes (the dataset has no stability annotation?)",
                headers={"expected": "scene-tasks", "epochs": "epochs (answers per scene-task)"},
            )
            + Markup('<p class="muted">Scenes left out of the stable subset, by reason:</p>')
            + html_table(tables["stable_exclusions"]),
        ),
        (
            "Bootstrap 95% intervals (answered only)",
            html_table(tables["bootstrap_answered"], percent=("estimate", "lo", "hi")),
        ),
        (
            "Paired comparisons (a minus b, scenes both answered, exact sign test)",
            html_table(pairs, percent=("a_score", "b_score", "diff", "lo", "hi"))
            if not pairs.empty
            else Markup("<p class='muted'>no model runs to compare</p>"),
        ),
    ]
    if not tables["metadata"].empty:
        out.insert(2, _metadata_section(tables["metadata"]))
    for diagnostic in part.diagnostics:
        table = tables[diagnostic.name]
        percent = (*diagnostic.percent, "complete")
        body = html_table(table, percent=percent, drop=_dropped(table))
        out.append((diagnostic.title, body))
    out.append(("Tokens, cost, latency, retries", usage_table(tables["usage"])))
    spending = spending_table(part)
    if not spending.empty:
        out.append(("Spending and the cost cap (--max-cost)", html_table(spending)))
    return out


def spending_table(part: ReportPart) -> pd.DataFrame:
    """Per capped run, as its last session left it (``run.json``): the caps, USD spent over
    all sessions, reserved (calls abandoned in flight, counted as spent by the next session)
    and left, and the pairs the cap kept from being sent."""
    rows = []
    for run in part.results.runs:
        budget = (run.manifest.get("last_session") or {}).get("budget") or {}
        if budget.get("cap") is None and budget.get("command_cap") is None:
            continue
        kept = [str(k) for k in budget.get("kept_by_cap") or []]
        lefts = [v for v in (budget.get("left"), budget.get("command_left")) if v is not None]
        rows.append(
            {
                "run": run.label, "cap $": budget.get("cap"),
                "command cap $": budget.get("command_cap"), "spent $": budget.get("spent"),
                "reserved $": budget.get("reserved"), "left $": min(lefts),
                "kept by the cap": len(kept),
                "pairs kept": ", ".join(kept[:20]) + (" ..." if len(kept) > 20 else ""),
            }
        )  # fmt: skip
    return pd.DataFrame(rows)


def epoch_columns(table: pd.DataFrame) -> list[str]:
    """``["epochs"]`` when a run of ``table`` asked its scene-tasks more than once (its counts
    are of answers, not scene-tasks), else nothing: a column of 1s says nothing."""
    if "epochs" in table.columns and bool((table["epochs"] > 1).any()):
        return ["epochs"]
    return []


def _dropped(table: pd.DataFrame) -> tuple[str, ...]:
    return ("adapter", "model", *([] if epoch_columns(table) else ["epochs"]))


def _metadata_section(frame: pd.DataFrame) -> tuple[str, Markup]:
    note = Markup(
        "<p class='muted'>What adapters measured about their own answers (see each adapter's "
        "docs), per horizon: the median over scenes of each number, the share of scenes where "
        "a yes/no measure holds, the count of scenes of a text measure (e.g. a reason for not "
        "answering). A scene counts once, its value the mean over its answers (tasks, epochs). "
        "Counts of scenes, means and maxima: "
        "<i>tables/metadata.csv</i>.</p>"
    )
    return "Adapters' own measurements by horizon", note + html_table(metadata_by_horizon(frame))


USAGE_HEADERS = {
    "calls": "calls", "input_tokens": "in tok", "output_tokens": "out tok",
    "reasoning_tokens": "reason tok", "cached_tokens": "cached tok", "cost": "cost $",
    "cost_unknown": "cost unknown", "latency_mean": "latency mean ms",
    "latency_median": "latency median ms", "retries": "retries", "ok": "ok",
    "parse_error": "parse err", "refused": "refused", "cut": "cut", "empty": "empty",
    "api_error": "api err", "missing": "missing",
    "tokens_per_call": "tok/call",
}  # fmt: skip


def usage_table(frame: pd.DataFrame) -> Markup:
    """The usage table with short headers and latencies in milliseconds."""
    shown = frame.copy()
    for name in ("latency_mean", "latency_median"):
        shown[name] = (1000 * shown[name]).round(0)
    shown["tokens_per_call"] = shown["tokens_per_call"].round(0)
    return html_table(shown, headers=USAGE_HEADERS)
