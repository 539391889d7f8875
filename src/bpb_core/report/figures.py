"""The charts of one report part, as PNG bytes keyed by title."""

from __future__ import annotations

from typing import TYPE_CHECKING

from bpb_core.report import charts as ch
from bpb_core.report.horizon_chart import accuracy_by_horizon
from bpb_core.results.tables import metrics

if TYPE_CHECKING:
    from bpb_core.report.parts import Completeness, ReportPart


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
        ),
        "Accuracy by horizon": accuracy_by_horizon(
            tables["accuracy_answered"], order, suites, names, min_complete=rule.min_complete
        ),
    }  # fmt: skip
    for diagnostic in part.diagnostics:
        png = diagnostic.chart(tables[diagnostic.name])
        if png is not None:
            pngs[diagnostic.title] = png
    return pngs
