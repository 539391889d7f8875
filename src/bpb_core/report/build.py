"""Build a report: every derived table, PNG charts, CSV/Parquet/Markdown/LaTeX exports and one
HTML page.

Runs on different datasets answered different questions, so a report never ranks them
together: :func:`report_parts` splits the results by dataset hash into parts and derives each
part's tables on its own (:func:`report_tables` is pure: frames in, frames out).
:func:`build_report` writes, when given an output folder::

    OUT/report.html            self-contained page (charts and gallery embedded)
    OUT/charts/*.png           leaderboards, accuracy by horizon, the diagnostics' charts
    OUT/gallery/*.png          the failure gallery's overlays
    OUT/tables/*.csv           every derived table (+ .md and .tex of the paper's tables)
    OUT/units.{csv,parquet}    the scored units frame
    OUT/calls.{csv,parquet}    the per-call frame

With several datasets, chart and table names start with the dataset's short hash.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from bpb_core.capabilities import ReportsMetrics
from bpb_core.errors import BadInput, PluginBug, WriteRefused, blamed, writing
from bpb_core.plugin_calls import returned
from bpb_core.registry import DiagnosticInfo, ReferenceInfo
from bpb_core.report import charts as ch
from bpb_core.report.sections import (
    build_cases,
    headline,
    part_json,
    render_page,
    scene_totals,
    sections,
    write_exports,
)
from bpb_core.results.frames import Results, load_results
from bpb_core.results.reading import RunFolder
from bpb_core.results.tables import (
    DEFAULT_MIN_COMPLETE,
    RUN_COLUMNS,
    UNANSWERED,
    accuracy,
    by_horizon,
    cell_levels,
    leaderboard,
    metadata_table,
    metrics,
    stable_exclusions,
    summary,
    usage,
)
from bpb_core.results.uncertainty import all_pairs, bootstrap_ci, reference_table
from bpb_core.scored_units import object_origin

if TYPE_CHECKING:
    from bpb_core.interfaces import Diagnostic, Scorer
    from bpb_core.registry import Registry


@dataclass(frozen=True)
class Completeness:
    """How much of a cell must be answered to count (see
    :mod:`bpb_core.results.tables`)."""

    min_complete: float = DEFAULT_MIN_COMPLETE
    include_incomplete: bool = False


@dataclass(frozen=True)
class ReportPart:
    """The runs on one dataset, with every derived table (the diagnostics' under their names)
    and the diagnostics shown."""

    dataset: str
    results: Results
    tables: dict[str, pd.DataFrame]
    diagnostics: tuple[Diagnostic, ...] = ()
    metric_notes: dict[str, Mapping[str, str]] = field(default_factory=dict)
    """Per task with a ``<task>_metrics`` table: its metrics and what each says."""
    diagnostic_tasks: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """Per diagnostic, the tasks it looks at."""
    origins: dict[str, str] = field(default_factory=dict)
    """Per diagnostic, who supplied it (``Registered.origin``), for one-line plugin errors."""
    scenes: str = ""
    """The part's scenes in a few words when its dataset's runs were asked different scenes
    (each scene set is a part of its own), else empty."""
    section: int = 0
    """The part's number among its dataset's scene sets (0: the dataset is one part)."""

    def origin(self, diagnostic: str) -> str:
        """Who supplied ``diagnostic`` (its name when not known)."""
        return self.origins.get(diagnostic, f"diagnostic {diagnostic!r}")

    def left_out(self, diagnostic: str) -> list[str]:
        """Runs a diagnostic's chart leaves out: a task the diagnostic looks at is left out of
        the leaderboards (a cell too incomplete); its table keeps them, with their
        completeness."""
        board = self.tables["leaderboard_answered"]
        wanted = set(self.diagnostic_tasks.get(diagnostic, ()))
        return [
            str(run) for run, short in zip(board["run"], board["short"], strict=True)
            if wanted & set(str(short).split(", "))
        ]  # fmt: skip

    @property
    def path(self) -> str:
        """The dataset folder the runs name (the first run's)."""
        return str(self.results.runs[0].dataset) if self.results.runs else ""

    @property
    def short_id(self) -> str:
        """The first 12 characters of the dataset hash (a path's last part when no hash)."""
        base = self.dataset[:12] if "/" not in self.dataset else self.dataset.rsplit("/", 1)[1]
        return f"{base}-{self.section}" if self.section else base

    @property
    def title(self) -> str:
        """The part's heading: its dataset and, when split, its scenes."""
        return f"{self.short_id} ({self.path})" + (f": {self.scenes}" if self.scenes else "")


def report_parts(
    results: Results,
    registry: Registry,
    *,
    n_boot: int = 2000,
    seed: int = 0,
    completeness: Completeness | None = None,
) -> tuple[ReportPart, ...]:
    """One :class:`ReportPart` per dataset, with the diagnostics of the tasks that ran on it."""
    parts = []
    sections: Counter[str] = Counter()
    for part, scenes in by_dataset(results):
        diagnostics = tuple(registry.diagnostics_for(part.tasks))
        scorers = {task: registry.scorer_for(task) for task in part.tasks}
        infos = registry.entries("diagnostic")
        origins = {d.name: infos[d.name].origin for d in diagnostics if d.name in infos}
        scored_by = {task: registry.scorer_entry(task).origin for task in scorers}
        tables = report_tables(
            part, diagnostics, n_boot=n_boot, seed=seed, completeness=completeness,
            scorers=scorers, origins=origins, scorer_origins=scored_by,
            references=registry.references(),
        )  # fmt: skip
        dataset = part.runs[0].dataset_id if part.runs else ""
        notes: dict[str, Mapping[str, str]] = {
            task: _notes(scorer, scored_by[task])
            for task, scorer in scorers.items()
            if isinstance(scorer, ReportsMetrics)
        }
        looks = {d.name: _tasks_of(infos.get(d.name)) for d in diagnostics}
        sections[dataset] += 1
        section = sections[dataset] if scenes else 0
        parts.append(
            ReportPart(dataset, part, tables, diagnostics, notes, looks, origins, scenes, section)
        )
    return tuple(parts)


def by_dataset(results: Results) -> list[tuple[Results, str]]:
    """``results`` split by dataset (the hash each run records), then by the scenes each run
    was asked: runs on different datasets answered different questions, and runs asked
    different scenes of one dataset (``--horizons 1`` beside a full run, ``--sample``) have
    means over different scenes, so neither is ever ranked together. Datasets in the order
    their first run was read; each part with the label of its scenes (horizons and count) when
    its dataset's runs were split, else ``""``."""
    pairs = results.units[["run", "scene_id"]].drop_duplicates().astype(str)
    asked: dict[str, frozenset[str]] = {
        str(run): frozenset(group["scene_id"]) for run, group in pairs.groupby("run")
    }
    groups: dict[tuple[str, frozenset[str]], list[RunFolder]] = {}
    for run in results.runs:
        key = (run.dataset_id, asked.get(run.label, frozenset()))
        groups.setdefault(key, []).append(run)
    if len(groups) <= 1:
        return [(results, "")]
    split = Counter(dataset for dataset, _ in groups)
    parts = []
    for (dataset, _), runs in groups.items():
        labels = {run.label for run in runs}
        units, calls = _only(results.units, labels), _only(results.calls, labels)
        tasks = {str(t) for t in units["task"].unique()}
        suites = tuple(s for s in results.suites if set(s.weights) <= tasks)
        label = scene_label(units) if split[dataset] > 1 else ""
        parts.append((Results(units, calls, tuple(runs), suites), label))
    return parts


def scene_label(units: pd.DataFrame) -> str:
    """The scenes of ``units`` in a few words: their horizons and how many."""
    horizons = sorted(float(h) for h in units["horizon"].unique().tolist())
    count = units["scene_id"].nunique()
    noun = "scene" if count == 1 else "scenes"
    return f"horizons {', '.join(f'{h:g}' for h in horizons)} s, {count} {noun}"


def _only(frame: pd.DataFrame, runs: set[str]) -> pd.DataFrame:
    part = frame[frame["run"].astype(str).isin(runs)].reset_index(drop=True)
    for name in part.columns:
        if isinstance(part[name].dtype, pd.CategoricalDtype):
            part[name] = part[name].cat.remove_unused_categories()
    return part


def _table(diagnostic: Diagnostic, origin: str, results: Results) -> pd.DataFrame:
    what = f"diagnostic {diagnostic.name!r}: table()"
    with blamed(origin, what):
        table = diagnostic.table(results)
    if isinstance(table, pd.DataFrame):
        return table
    raise returned(origin, what, type(table).__name__, "a pandas DataFrame")


def _tasks_of(entry: object) -> tuple[str, ...]:
    info = getattr(entry, "info", None)
    return tuple(info.tasks) if isinstance(info, DiagnosticInfo) else ()


def report_tables(
    results: Results,
    diagnostics: Sequence[Diagnostic] = (),
    *,
    n_boot: int = 2000,
    seed: int = 0,
    completeness: Completeness | None = None,
    scorers: Mapping[str, Scorer] | None = None,
    origins: Mapping[str, str] | None = None,
    scorer_origins: Mapping[str, str] | None = None,
    references: Sequence[ReferenceInfo] = (),
) -> dict[str, pd.DataFrame]:
    """Every table of a report, derived from ``results`` (nothing is written or printed).

    Leaderboards leave out a task with a cell under the completeness threshold (unless
    ``include_incomplete``); accuracy tables carry each cell's ``level`` (full, partial,
    short); bootstrap intervals are blanked where the leaderboard is; paired comparisons use
    the scenes both runs answered. A scorer that :class:`~bpb_core.capabilities.ReportsMetrics`
    adds the table ``<task>_metrics``. ``origins`` names who supplied each diagnostic, for
    the :class:`~bpb_core.errors.PluginBug` raised when one fails or returns no DataFrame;
    ``scorer_origins`` names who supplied each task's scorer, for its ``task_metrics``.
    ``references`` (published figures) give the table ``references``: each figure beside the
    runs of its model (:func:`~bpb_core.results.uncertainty.reference_table`).
    """
    rule = completeness or Completeness()
    units, calls, suites, scenes = results.units, results.calls, results.suites, results.scenes
    keep: dict[str, Any] = {**asdict(rule), "scenes": scenes}
    boot: dict[str, Any] = {"n_boot": n_boot, "seed": seed, "scenes": scenes}
    tables = {
        "summary": summary(units, suites, **keep),
        "leaderboard": leaderboard(units, suites, **keep),
        "leaderboard_answered": leaderboard(units, suites, view="answered", **keep),
        "leaderboard_stable": leaderboard(units, suites, stable_only=True, **keep),
        "by_horizon": by_horizon(units, **keep),
        "by_horizon_answered": by_horizon(units, view="answered", **keep),
        "pairs": all_pairs(units, suites, view="answered", **boot),
        "stable_exclusions": stable_exclusions(units),
        "usage": usage(calls),
        "metadata": metadata_table(calls),
        "references": reference_table(units, suites, references, **boot),
    }
    for suffix, view in (("", "strict"), ("_answered", "answered")):
        acc = accuracy(units, view=view, scenes=scenes)  # type: ignore[arg-type]
        tables[f"accuracy{suffix}"] = acc.assign(level=cell_levels(acc, rule.min_complete))
        ci = bootstrap_ci(units, suites, view=view, **boot)  # type: ignore[arg-type]
        tables[f"bootstrap{suffix}"] = _blank(ci, tables[f"leaderboard{suffix}"])
    tables["completeness"] = tables["accuracy"].drop(columns=["accuracy", "scenes"])
    done = tables["leaderboard"].set_index("run")[["completeness", "epochs"]]
    for diagnostic in diagnostics:
        origin = (origins or {}).get(diagnostic.name, f"diagnostic {diagnostic.name!r}")
        tables[diagnostic.name] = _with_completeness(_table(diagnostic, origin, results), done)
    for task, scorer in (scorers or {}).items():
        if isinstance(scorer, ReportsMetrics):
            origin = (scorer_origins or {}).get(task) or object_origin(scorer)
            table = task_metrics(
                units, task, scorer, tables["leaderboard_answered"], rule, origin=origin
            )
            tables[f"{task}_metrics"] = _with_completeness(table, done)
    return tables


def task_metrics(
    units: pd.DataFrame,
    task: str,
    scorer: ReportsMetrics,
    board: pd.DataFrame,
    rule: Completeness,
    *,
    origin: str = "",
) -> pd.DataFrame:
    """A scorer's metrics on the task's answered units, blanked (NaN) for runs whose task the
    leaderboard left out.

    Raises:
        PluginBug: ``task_metrics`` raised or returned no DataFrame with the run columns and
            one column per metric, or ``metric_notes`` is no dict of strings, naming ``origin``
            (who supplied the scorer).
    """
    answered = units[(units["task"] == task) & ~units["status"].isin(UNANSWERED)]
    table = _metrics(scorer, origin or object_origin(scorer), answered)
    if not rule.include_incomplete:
        short = board.set_index("run")["short"].astype(str)
        left_out = [task in short.get(str(run), "").split(", ") for run in table["run"]]
        table.loc[left_out, list(scorer.metric_notes)] = np.nan
    return table


def _notes(scorer: ReportsMetrics, origin: str) -> dict[str, str]:
    """The scorer's ``metric_notes``, if it maps each metric column to its line (what reads it
    next, the report's pages and tables, would fail on anything else far from its cause)."""
    notes = scorer.metric_notes
    if isinstance(notes, Mapping) and all(
        isinstance(name, str) and isinstance(note, str) for name, note in notes.items()
    ):
        return dict(notes)
    shown = repr(notes) if len(repr(notes)) <= 60 else type(notes).__name__
    raise PluginBug(
        f"{origin}: scorer {getattr(scorer, 'name', type(scorer).__name__)!r}: metric_notes is "
        f"{shown}; expected a dict of metric column (str) -> one line (str)"
    )


def _metrics(scorer: ReportsMetrics, origin: str, answered: pd.DataFrame) -> pd.DataFrame:
    what = f"scorer {getattr(scorer, 'name', type(scorer).__name__)!r}: task_metrics()"
    notes = _notes(scorer, origin)
    with blamed(origin, what):
        table = scorer.task_metrics(answered)
    wanted = [*RUN_COLUMNS, *notes]
    if isinstance(table, pd.DataFrame) and set(wanted) <= set(table.columns):
        return table
    got = type(table).__name__
    if isinstance(table, pd.DataFrame):
        got = f"a DataFrame with columns {list(table.columns)}"
    raise returned(origin, what, got, f"a DataFrame with the columns {', '.join(wanted)}")


def _with_completeness(table: pd.DataFrame, done: pd.DataFrame) -> pd.DataFrame:
    """A diagnostic's table with each run's completeness and epochs after the run columns: a
    diagnostic of a half-answered run says less than its numbers suggest, and its counts are
    of answers, each scene-task counted once per epoch (``--epochs``)."""
    if "run" not in table.columns or "complete" in table.columns:
        return table
    at = next((i for i, c in enumerate(table.columns) if c not in RUN_COLUMNS), len(table.columns))
    out = table.copy()
    runs = out["run"].astype(str)
    out.insert(at, "complete", runs.map(done["completeness"]).astype("float64"))
    if "epochs" not in out.columns:
        out.insert(at + 1, "epochs", runs.map(done["epochs"]).fillna(1).astype("int64"))
    return out


def _blank(ci: pd.DataFrame, board: pd.DataFrame) -> pd.DataFrame:
    """Bootstrap rows blanked where the leaderboard left the score out (too incomplete)."""
    if ci.empty:
        return ci
    scores = board.set_index("run")
    left_out = [
        metric not in scores.columns or bool(np.isnan(scores.loc[run, metric]))
        for run, metric in zip(ci["run"], ci["metric"], strict=True)
    ]
    out = ci.copy()
    out.loc[left_out, ["estimate", "lo", "hi"]] = np.nan
    return out


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
        cases += build_cases(part.results, scorers, gallery_size, origins)
        answered += len(scene_totals(part.results))
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
        "Leaderboards": ch.png(ch.leaderboard_figure(
            board, scores, tables["bootstrap_answered"], names,
            xlabel="mean accuracy over horizons, answered only (%)",
            unasked=unasked(part, scores),
        )),
        "Accuracy by horizon": ch.png(ch.by_horizon_figure(
            tables["accuracy_answered"], order, suites, names, min_complete=rule.min_complete
        )),
    }  # fmt: skip
    for task, notes in part.metric_notes.items():
        table = part.tables[f"{task}_metrics"]
        shown = [m for m in notes if table[m].notna().any()]
        if not shown:
            continue
        title = f"{names.get(task, task)}: metrics beside accuracy"
        pngs[title] = ch.png(ch.leaderboard_figure(
            table, shown, None, {m: f"{task} {m.replace('_', ' ')}" for m in shown},
            xlabel="answered only (%)", no_value="no value (undefined, or too incomplete)",
        ))  # fmt: skip
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
