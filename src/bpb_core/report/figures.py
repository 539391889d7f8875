"""The charts of one report part, as PNG bytes keyed by title."""

from __future__ import annotations

from typing import TYPE_CHECKING

from bpb_core.errors import PluginBug, blamed
from bpb_core.report import charts as ch
from bpb_core.report.horizon_chart import accuracy_by_horizon
from bpb_core.results.tables import metrics

if TYPE_CHECKING:
    import pandas as pd

    from bpb_core.interfaces import Diagnostic
    from bpb_core.report.parts import Completeness, ReportPart


def unasked(part: ReportPart, scores: list[str]) -> dict[str, list[str]]:
    """Per task or suite of ``scores``, the runs not asked it (a suite: not all its tasks)."""
    need = {s.name: set(s.weights) for s in part.results.suites}
    out: dict[str, list[str]] = {}
    for metric in scores:
        tasks = need.get(metric, {metric})
        out[metric] = [run.label for run in part.results.runs if not tasks <= set(run.tasks)]
    return out


def chart_pngs(part: ReportPart, names: dict[str, str], rule: Completeness) -> dict[str, bytes]:
    """Leaderboards (answered only, incomplete tasks left out), accuracy by horizon (grouped
    bars, incomplete cells greyed), then each diagnostic's chart."""
    tables, suites = part.tables, part.results.suites
    board = tables["leaderboard_answered"]
    order = board["run"].astype(str).tolist()
    scores = metrics(part.results.units, suites)
    pngs = {
        "Leaderboards": ch.leaderboards(
            board, scores, tables["bootstrap_answered"], names,
            xlabel="mean accuracy over horizons, answered only (%)",
            unasked=unasked(part, scores),
        ),
        "Accuracy by horizon": accuracy_by_horizon(
            tables["accuracy_answered"], order, suites, names, min_complete=rule.min_complete
        ),
    }  # fmt: skip
    for task, notes in part.metric_notes.items():
        table = part.tables[f"{task}_metrics"]
        shown = [m for m in notes if table[m].notna().any()]
        if not shown:
            continue
        title = f"{names.get(task, task)}: metrics beside accuracy"
        pngs[title] = ch.leaderboards(
            table, shown, None, {m: f"{task} {m.replace('_', ' ')}" for m in shown},
            xlabel="answered only (%)", no_value="no value (undefined, or too incomplete)",
        )  # fmt: skip
    for diagnostic in part.diagnostics:
        table = tables[diagnostic.name]
        left_out = [] if rule.include_incomplete else diagnostic_left_out(part, diagnostic.name)
        if "run" in table.columns and left_out:
            table = table[~table["run"].astype(str).isin(left_out)]
        png = _chart(part, diagnostic, table) if not table.empty else None
        if png is not None:
            pngs[diagnostic.title] = png
    return pngs


def _chart(part: ReportPart, diagnostic: Diagnostic, table: pd.DataFrame) -> bytes | None:
    origin = part.origin(diagnostic.name)
    with blamed(origin, f"diagnostic {diagnostic.name!r}: chart()"):
        png = diagnostic.chart(table)
    if png is not None and not isinstance(png, bytes):
        raise PluginBug(
            f"{origin}: diagnostic {diagnostic.name!r}: chart() returned "
            f"{type(png).__name__}; expected PNG bytes or None"
        )
    return png


def diagnostic_left_out(part: ReportPart, name: str) -> list[str]:
    """Runs a diagnostic's chart leaves out: too incomplete in one of the diagnostic's tasks
    (its table keeps them, with their completeness)."""
    return part.too_incomplete(part.diagnostic_tasks.get(name, ()))


def chart_notes(part: ReportPart, rule: Completeness) -> dict[str, str]:
    """A line under each chart that leaves runs out, naming them."""
    if rule.include_incomplete:
        return {}
    notes = {}
    for diagnostic in part.diagnostics:
        left_out = diagnostic_left_out(part, diagnostic.name)
        if left_out:
            notes[diagnostic.title] = f"left out as too incomplete: {', '.join(left_out)}"
    return notes
