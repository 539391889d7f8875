"""Build a report: every derived table, PNG charts, CSV/Parquet/Markdown/LaTeX exports and one
HTML page.

Runs are grouped by the dataset they answered (:mod:`bpb_core.report.parts`); each dataset is a
part of its own, never one leaderboard. :func:`build_report` writes, when given an output
folder::

    OUT/report.html            self-contained page (charts and gallery embedded)
    OUT/charts/*.png           leaderboards, accuracy by horizon, the diagnostics' charts
    OUT/gallery/*.png          the failure gallery's overlays
    OUT/tables/*.csv           every derived table (+ .md and .tex of the paper's tables)
    OUT/units.{csv,parquet}    the scored units frame
    OUT/calls.{csv,parquet}    the per-call frame

With several datasets, chart and table names start with the dataset's short hash.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from bpb_core.errors import BadInput, WriteRefused, blamed, writing
from bpb_core.plugin_calls import returned
from bpb_core.report import charts as ch, gallery
from bpb_core.report.exports import part_json, write_exports
from bpb_core.report.parts import Completeness, ReportPart, report_parts, report_tables
from bpb_core.report.sections import headline, render_page, sections
from bpb_core.results.frames import Results, load_results
from bpb_core.results.tables import metrics

if TYPE_CHECKING:
    from bpb_core.interfaces import Diagnostic
    from bpb_core.registry import Registry

__all__ = ["Completeness", "Report", "ReportPart", "build_report", "report_tables"]


@dataclass(frozen=True)
class Report:
    """A built report: one part per dataset, the files written (if any) and the completeness
    rule applied."""

    parts: tuple[ReportPart, ...]
    files: dict[str, Path] = field(default_factory=dict)
    completeness: Completeness = field(default_factory=Completeness)

    @property
    def part(self) -> ReportPart:
        """The only part.

        Raises:
            BadInput: The runs answered several datasets (use :attr:`parts`).
        """
        if len(self.parts) != 1:
            names = ", ".join(p.short_id for p in self.parts)
            raise BadInput(f"the runs answered {len(self.parts)} datasets ({names}): see .parts")
        return self.parts[0]

    @property
    def results(self) -> Results:
        """The only part's results (see :attr:`part`)."""
        return self.part.results

    @property
    def tables(self) -> dict[str, pd.DataFrame]:
        """The only part's tables, the diagnostics' among them under their names."""
        return self.part.tables

    @property
    def diagnostics(self) -> tuple[Diagnostic, ...]:
        """The only part's diagnostics."""
        return self.part.diagnostics

    def summary_json(self) -> dict[str, Any]:
        """JSON-ready summary for scripts. One dataset: its leaderboards, intervals, accuracy
        by horizon, completeness, usage and diagnostics at the top level. Several: the same
        per dataset under ``datasets`` (never one leaderboard)."""
        rule = asdict(self.completeness)
        files = {name: str(path) for name, path in self.files.items()}
        parts = [part_json(p) for p in self.parts]
        if len(parts) == 1:
            return {**parts[0], "completeness_rule": rule, "files": files}
        return {"datasets": parts, "completeness_rule": rule, "files": files}


def build_report(
    run_dirs: Path | str | Iterable[Path | str],
    out: Path | str | None = None,
    *,
    n_boot: int = 2000,
    seed: int = 0,
    gallery_size: int = 8,
    registry: Registry | None = None,
    completeness: Completeness | None = None,
) -> Report:
    """Score run folders and derive every table per dataset (with the diagnostics of the tasks
    that ran); with ``out``, also write charts, exports and ``report.html`` there.

    Raises:
        BadInput: No run folder found, or a run, answer or ground-truth file cannot be read;
            ``out`` given without the ``report`` extra installed.
        WriteRefused: The system refused to write a file of the report (names it).
    """
    from bpb_core.registry import make_registry

    if out is not None:
        need_report_extra()
    registry = registry if registry is not None else make_registry()
    rule = completeness or Completeness()
    results = load_results(run_dirs, registry=registry)
    parts = report_parts(results, registry, n_boot=n_boot, seed=seed, completeness=rule)
    report = Report(parts, completeness=rule)
    if out is None:
        return report
    try:
        files = write_report(report, Path(out), registry, gallery_size=gallery_size)
    except WriteRefused as exc:
        raise WriteRefused(
            f"{exc}; the report in {out} is incomplete (the runs it reads are untouched): "
            "make room, then run it again"
        ) from None
    return Report(parts, files, rule)


def need_report_extra() -> None:
    """Refuse, before any scoring, a written report the installed packages cannot draw.

    Raises:
        BadInput: matplotlib (charts) or pyarrow (Parquet) is missing; names the extra.
    """
    import importlib.util

    missing = [m for m in ("matplotlib", "pyarrow") if importlib.util.find_spec(m) is None]
    if missing:
        raise BadInput(
            f"a written report (--out) needs {' and '.join(missing)}: "
            "pip install 'bpb[report]' (the terminal report and --json work without them)"
        )


def titles(results: Results, registry: Registry) -> dict[str, str]:
    """Display titles of the tasks and suites (a task no longer installed keeps its name)."""
    found = {s.name: s.title or s.name for s in results.suites}
    for task in results.tasks:
        known = task in registry.names("task")
        found[task] = (registry.task_info(task).title if known else "") or task
    return found


def write_report(
    report: Report, out: Path, registry: Registry, *, gallery_size: int = 8
) -> dict[str, Path]:
    """Write charts, gallery images, exports and ``report.html`` under ``out``.

    Raises:
        WriteRefused: The system refused a write (a full disk): names the file.
    """
    files: dict[str, Path] = {}
    for sub in ("charts", "gallery", "tables"):
        with writing(out / sub):
            (out / sub).mkdir(parents=True, exist_ok=True)
    several = len(report.parts) > 1
    pages, cases = [], []
    names: dict[str, str] = {}  # display titles of the tasks, for the gallery
    answered = 0  # fully answered (run, scene) pairs: what the gallery picks from
    for part in report.parts:
        prefix = f"{part.short_id}_" if several else ""
        named = titles(part.results, registry)
        names |= named
        pngs = chart_pngs(part, named, report.completeness)
        for title, png in pngs.items():
            path = out / "charts" / f"{prefix}{_slug(title)}.png"
            files[f"chart:{prefix}{title}"] = _write(path, png)
        files.update(write_exports(part, out, prefix, report.completeness))
        scorers = {task: registry.scorer_for(task) for task in part.results.tasks}
        origins = {task: registry.scorer_entry(task).origin for task in scorers}
        cases += gallery.build_cases(part.results, scorers, gallery_size, origins)
        answered += len(gallery.scene_totals(part.results))
        pages.append(
            {
                "name": part.title,
                "runs": run_items(part),
                "headline": headline(part, report.completeness),
                "charts": pngs,
                "chart_notes": chart_notes(part, report.completeness),
                "sections": sections(part, report.completeness),
            }
        )
    for i, case in enumerate(cases):
        if case.png:
            name = f"{i:02d}_{_slug(case.run)}_{case.scene_id}.png"
            files[f"gallery:{i}"] = _write(out / "gallery" / name, case.png)
    files.update(_export_frames(report, out))
    page = render_page(
        title="bpb report", parts=pages, cases=cases, answered=answered, titles=names
    )
    files["html"] = _write(out / "report.html", page.encode("utf-8"))
    return files


def run_items(part: ReportPart) -> list[dict[str, Any]]:
    """The runs of a part, for the page's run list."""
    return [
        {
            "label": run.label,
            "adapter": run.adapter,
            "model": run.model,
            "tasks": ", ".join(run.tasks),
            "scenes": len(run.scene_keys),
            "dataset": str(run.dataset),
            "hash": str(run.manifest.get("dataset_hash") or "")[:12],
            "baseline": run.baseline,
        }
        for run in part.results.runs
    ]


def _write(path: Path, data: bytes) -> Path:
    with writing(path):
        path.write_bytes(data)
    return path


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in text.lower()).strip("_")


def _export_frames(report: Report, out: Path) -> dict[str, Path]:
    files: dict[str, Path] = {}
    for name in ("units", "calls"):
        frames = [getattr(p.results, name) for p in report.parts]
        frame = frames[0] if len(frames) == 1 else pd.concat(frames, ignore_index=True)
        for suffix, write in ((".csv", frame.to_csv), (".parquet", frame.to_parquet)):
            files[name + suffix] = out / (name + suffix)
            with writing(files[name + suffix]):
                write(files[name + suffix], index=False)
    return files


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
        "Accuracy by horizon": ch.accuracy_by_horizon(
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
        left_out = [] if rule.include_incomplete else part.left_out(diagnostic.name)
        if "run" in table.columns and left_out:
            table = table[~table["run"].astype(str).isin(left_out)]
        png = _chart(part, diagnostic, table) if not table.empty else None
        if png is not None:
            pngs[diagnostic.title] = png
    return pngs


def _chart(part: ReportPart, diagnostic: Diagnostic, table: pd.DataFrame) -> bytes | None:
    origin, what = part.origin(diagnostic.name), f"diagnostic {diagnostic.name!r}: chart()"
    with blamed(origin, what):
        png = diagnostic.chart(table)
    if png is None or isinstance(png, bytes):
        return png
    raise returned(origin, what, type(png).__name__, "PNG bytes or None")


def chart_notes(part: ReportPart, rule: Completeness) -> dict[str, str]:
    """A line under each chart that leaves runs out, naming them."""
    if rule.include_incomplete:
        return {}
    notes = {}
    for diagnostic in part.diagnostics:
        left_out = part.left_out(diagnostic.name)
        if left_out:
            notes[diagnostic.title] = f"left out as too incomplete: {', '.join(left_out)}"
    return notes
