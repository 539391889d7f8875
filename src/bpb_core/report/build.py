"""Build a report: every derived table, PNG charts, CSV/Parquet exports and one HTML page.

:func:`report_tables` is pure (frames in, frames out). :func:`build_report` also writes files
when given an output folder::

    OUT/report.html            self-contained page (charts and gallery embedded)
    OUT/charts/*.png           leaderboards, accuracy vs horizon, the diagnostics' charts
    OUT/gallery/*.png          the failure gallery's overlays
    OUT/tables/*.csv           every derived table
    OUT/units.{csv,parquet}    the scored units frame
    OUT/calls.{csv,parquet}    the per-call frame
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from html import escape
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from bpb_core.report import charts as ch, gallery, html
from bpb_core.results.frames import Results, load_results
from bpb_core.results.metadata import metadata_by_horizon, metadata_table
from bpb_core.results.tables import (
    accuracy,
    by_horizon,
    leaderboard,
    metrics,
    stable_exclusions,
    summary,
    summary_records,
)
from bpb_core.results.uncertainty import all_pairs, bootstrap_ci
from bpb_core.results.usage import usage

if TYPE_CHECKING:
    from bpb_core.interfaces import Diagnostic
    from bpb_core.registry import Registry


@dataclass(frozen=True)
class Report:
    """A built report: the results, every derived table (the diagnostics' among them, under
    their names), the diagnostics shown and the files written (if any)."""

    results: Results
    tables: dict[str, pd.DataFrame]
    files: dict[str, Path] = field(default_factory=dict)
    diagnostics: tuple[Diagnostic, ...] = ()

    def summary_json(self) -> dict[str, Any]:
        """JSON-ready summary for scripts: leaderboard, CIs, the stable-subset leaderboard,
        every diagnostic and the files written."""
        return {
            "leaderboard": summary_records(self.results.units, self.results.suites),
            "suites": {s.name: dict(s.weights) for s in self.results.suites},
            "bootstrap": _records(self.tables["bootstrap"]),
            "stable": _records(self.tables["leaderboard_stable"]),
            "stable_exclusions": _records(self.tables["stable_exclusions"]),
            "diagnostics": {d.name: _records(self.tables[d.name]) for d in self.diagnostics},
            "files": {name: str(path) for name, path in self.files.items()},
        }


def _records(frame: pd.DataFrame) -> list[dict[str, Any]]:
    cleaned = frame.astype(object).where(frame.notna(), None)
    return [{str(k): v for k, v in row.items()} for row in cleaned.to_dict(orient="records")]


def report_tables(
    results: Results,
    diagnostics: Sequence[Diagnostic] = (),
    *,
    n_boot: int = 2000,
    seed: int = 0,
) -> dict[str, pd.DataFrame]:
    """Every table of a report, derived from ``results`` (nothing is written or printed)."""
    units, calls, suites = results.units, results.calls, results.suites
    tables = {
        "summary": summary(units, suites),
        "leaderboard": leaderboard(units, suites),
        "leaderboard_answered": leaderboard(units, suites, view="answered"),
        "leaderboard_stable": leaderboard(units, suites, stable_only=True),
        "stable_exclusions": stable_exclusions(units),
        "accuracy": accuracy(units),
        "accuracy_answered": accuracy(units, view="answered"),
        "by_horizon": by_horizon(units),
        "by_horizon_answered": by_horizon(units, view="answered"),
        "bootstrap": bootstrap_ci(units, suites, n_boot=n_boot, seed=seed),
        "pairs": all_pairs(units, suites, n_boot=n_boot, seed=seed),
        "usage": usage(calls),
        "metadata": metadata_table(calls),
    }
    for diagnostic in diagnostics:
        tables[diagnostic.name] = diagnostic.table(results)
    return tables


def build_report(
    run_dirs: Path | str | Iterable[Path | str],
    out: Path | str | None = None,
    *,
    n_boot: int = 2000,
    seed: int = 0,
    gallery_size: int = 8,
    registry: Registry | None = None,
) -> Report:
    """Score run folders and derive every table (with the diagnostics of the tasks that ran);
    with ``out``, also write charts, exports and ``report.html`` there.

    Raises:
        BadInput: No run folder found, or a run, answer or ground-truth file cannot be read.
    """
    from bpb_core.registry import make_registry

    registry = registry if registry is not None else make_registry()
    results = load_results(run_dirs, registry=registry)
    diagnostics = tuple(registry.diagnostics_for(results.tasks))
    tables = report_tables(results, diagnostics, n_boot=n_boot, seed=seed)
    report = Report(results, tables, diagnostics=diagnostics)
    if out is None:
        return report
    files = write_report(report, Path(out), registry, gallery_size=gallery_size)
    return Report(results, tables, files, diagnostics)


def titles(results: Results, registry: Registry) -> dict[str, str]:
    """Display titles of the tasks and suites (a task no longer installed keeps its name)."""
    found = {s.name: s.title or s.name for s in results.suites}
    for task in results.tasks:
        known = task in registry.names("task")
        found[task] = (registry.task_info(task).title if known else "") or task
    return found


def chart_pngs(report: Report, names: dict[str, str]) -> dict[str, bytes]:
    """The report's charts as PNG bytes, keyed by title: leaderboards, accuracy against
    horizon, then each diagnostic's chart."""
    tables, suites = report.tables, report.results.suites
    order = tables["leaderboard"]["run"].tolist()
    board = metrics(report.results.units, suites)
    pngs = {
        "Leaderboards": ch.leaderboards(tables["leaderboard"], board, tables["bootstrap"], names),
        "Accuracy vs horizon": ch.accuracy_vs_horizon(tables["accuracy"], order, suites, names),
    }
    for diagnostic in report.diagnostics:
        png = diagnostic.chart(tables[diagnostic.name])
        if png is not None:
            pngs[diagnostic.title] = png
    return pngs


def write_report(
    report: Report, out: Path, registry: Registry, *, gallery_size: int = 8
) -> dict[str, Path]:
    """Write charts, gallery images, CSV/Parquet exports and ``report.html`` under ``out``."""
    results, tables = report.results, report.tables
    files: dict[str, Path] = {}
    for sub in ("charts", "gallery", "tables"):
        (out / sub).mkdir(parents=True, exist_ok=True)
    pngs = chart_pngs(report, titles(results, registry))
    for title, png in pngs.items():
        files[f"chart:{title}"] = _write(out / "charts" / f"{_slug(title)}.png", png)
    scorers = {task: registry.scorer_for(task) for task in results.tasks}
    cases = gallery.build_cases(results, scorers, gallery_size)
    for i, case in enumerate(cases):
        if case.png:
            name = f"{i:02d}_{_slug(case.run)}_{case.scene_id}.png"
            files[f"gallery:{i}"] = _write(out / "gallery" / name, case.png)
    for name, frame in tables.items():
        files[f"table:{name}"] = out / "tables" / f"{name}.csv"
        frame.to_csv(files[f"table:{name}"], index=False)
    files.update(_export_frames(results, out))
    page = html.render(
        title="bpb report",
        runs=results.runs,
        headline=[("Leaderboard (strict)", _headline(tables, results))],
        sections=_sections(tables, report.diagnostics),
        charts=pngs,
        cases=cases,
    )
    files["html"] = _write(out / "report.html", page.encode("utf-8"))
    return files


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in text.lower()).strip("_")


def _export_frames(results: Results, out: Path) -> dict[str, Path]:
    files: dict[str, Path] = {}
    for name, frame in (("units", results.units), ("calls", results.calls)):
        files[f"{name}.csv"] = out / f"{name}.csv"
        frame.to_csv(files[f"{name}.csv"], index=False)
        files[f"{name}.parquet"] = out / f"{name}.parquet"
        frame.to_parquet(files[f"{name}.parquet"], index=False)
    return files


def _headline(tables: dict[str, pd.DataFrame], results: Results) -> str:
    board = tables["summary"].copy()
    first = results.suites[0].name if results.suites else None
    ci = tables["bootstrap"].pivot_table(
        index="run", columns="metric", values=["lo", "hi"], observed=True
    )
    if first is not None and not ci.empty:
        lo, hi = ci["lo"][first], ci["hi"][first]
        board[f"{first} 95% CI"] = [
            f"{100 * lo.get(r, float('nan')):.1f}–{100 * hi.get(r, float('nan')):.1f}%"
            for r in board["run"]
        ]
    suites = ", ".join(f"<i>{escape(s.name)}</i> ({escape(s.summary)})" for s in results.suites)
    note = (
        "<p class='muted'>Mean accuracy over horizons. Strict view: a missing answer, API error "
        "or parse error is wrong. <i>&lt;suite&gt;_answered</i> leaves out calls that never "
        "returned an answer; <i>completeness</i> is the share answered. Baselines are floors "
        "(stasis, straight, random) and the ceiling (oracle)."
        + (f" Suites: {suites}." if suites else "")
        + "</p>"
    )
    percent = [*metrics(results.units, results.suites), "completeness"]
    percent += [f"{s.name}_answered" for s in results.suites]
    return note + html.table(board, percent=percent)


def _metadata_section(frame: pd.DataFrame) -> tuple[str, str]:
    note = (
        "<p class='muted'>What adapters measured about their own answers (see each adapter's "
        "docs), per horizon: the median over scenes of each number, the count of scenes of a "
        "text measure (e.g. a reason for not answering). Counts, means and maxima: "
        "<i>tables/metadata.csv</i>.</p>"
    )
    return "Adapters' own measurements by horizon", note + html.table(metadata_by_horizon(frame))


def _sections(
    tables: dict[str, pd.DataFrame], diagnostics: Sequence[Diagnostic]
) -> list[tuple[str, str]]:
    pairs = tables["pairs"]
    horizons = [c for c in tables["by_horizon"].columns if c.startswith("h") or c == "mean"]
    scores = [
        c
        for c in tables["leaderboard_stable"].columns
        if c not in ("run", "adapter", "model", "baseline", "expected")
    ]
    sections = [
        ("Accuracy by horizon (strict)", html.table(tables["by_horizon"], percent=horizons)),
        (
            "Accuracy by horizon (answered only)",
            html.table(tables["by_horizon_answered"], percent=horizons),
        ),
        (
            "Leaderboard on stable scenes",
            html.table(
                tables["leaderboard_stable"],
                percent=scores,
                empty="no stable scenes (the dataset has no stability annotation?)",
            )
            + '<p class="muted">Scenes left out of the stable subset, by reason:</p>'
            + html.table(tables["stable_exclusions"]),
        ),
        (
            "Bootstrap 95% intervals",
            html.table(tables["bootstrap"], percent=("estimate", "lo", "hi")),
        ),
        (
            "Paired comparisons (a minus b, shared scenes, exact sign test)",
            html.table(pairs, percent=("a_score", "b_score", "diff", "lo", "hi"))
            if not pairs.empty
            else "<p class='muted'>no model runs to compare</p>",
        ),
    ]
    if not tables["metadata"].empty:
        sections.insert(2, _metadata_section(tables["metadata"]))
    for diagnostic in diagnostics:
        body = html.table(tables[diagnostic.name], percent=diagnostic.percent)
        sections.append((diagnostic.title, body))
    sections.append(("Tokens, cost, latency, retries", html.table(tables["usage"])))
    return sections
