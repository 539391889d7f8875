"""Build a report: every derived table, PNG charts, CSV/Parquet exports and one HTML page.

:func:`report_tables` is pure (frames in, frames out). :func:`build_report` also writes files
when given an output folder::

    OUT/report.html            self-contained page (charts and gallery embedded)
    OUT/charts/*.png           accuracy vs horizon, leaderboards, stasis, tolerance curve
    OUT/gallery/*.png          the failure gallery's overlays
    OUT/tables/*.csv           every derived table
    OUT/units.{csv,parquet}    the scored units frame
    OUT/calls.{csv,parquet}    the per-call frame
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from bpb_core.report import charts as ch
from bpb_core.report import gallery, html
from bpb_core.results import Results, load_results
from bpb_core.results.diagnostics import (
    confusion,
    distance_errors,
    stasis_index,
    tolerance_curve,
    usage,
)
from bpb_core.results.stats import all_pairs, bootstrap_ci
from bpb_core.results.tables import accuracy, by_horizon, leaderboard, summary, summary_records

if TYPE_CHECKING:
    from bpb_core.registry import Registry


@dataclass(frozen=True)
class Report:
    """A built report: the results, every derived table and the files written (if any)."""

    results: Results
    tables: dict[str, pd.DataFrame]
    files: dict[str, Path] = field(default_factory=dict)

    def summary_json(self) -> dict[str, Any]:
        """JSON-ready summary for scripts: leaderboard, CIs, stasis, the stable-subset
        leaderboard and the files written."""
        return {
            "leaderboard": summary_records(self.results.units),
            "bootstrap": _records(self.tables["bootstrap"]),
            "stasis": _records(self.tables["stasis"]),
            "stable": _records(self.tables["leaderboard_stable"]),
            "files": {name: str(path) for name, path in self.files.items()},
        }


def _records(frame: pd.DataFrame) -> list[dict[str, Any]]:
    cleaned = frame.astype(object).where(frame.notna(), None)
    return [{str(k): v for k, v in row.items()} for row in cleaned.to_dict(orient="records")]


def report_tables(
    results: Results, *, n_boot: int = 2000, seed: int = 0
) -> dict[str, pd.DataFrame]:
    """Every table of a report, derived from ``results`` (nothing is written or printed)."""
    units, calls = results.units, results.calls
    return {
        "summary": summary(units),
        "leaderboard": leaderboard(units),
        "leaderboard_answered": leaderboard(units, view="answered"),
        "leaderboard_stable": leaderboard(units, stable_only=True),
        "accuracy": accuracy(units),
        "accuracy_answered": accuracy(units, view="answered"),
        "by_horizon": by_horizon(units),
        "by_horizon_answered": by_horizon(units, view="answered"),
        "bootstrap": bootstrap_ci(units, n_boot=n_boot, seed=seed),
        "pairs": all_pairs(units, n_boot=n_boot, seed=seed),
        "confusion": confusion(units),
        "stasis": stasis_index(units),
        "distance": distance_errors(units),
        "distance_by_horizon": distance_errors(units, by_horizon=True),
        "tolerance": tolerance_curve(units),
        "usage": usage(calls),
    }


def build_report(
    run_dirs: Path | str | Iterable[Path | str],
    out: Path | str | None = None,
    *,
    n_boot: int = 2000,
    seed: int = 0,
    gallery_size: int = 8,
    registry: Registry | None = None,
) -> Report:
    """Score run folders and derive every table; with ``out``, also write charts, exports and
    ``report.html`` there.

    Raises:
        BadInput: No run folder found, or a run, answer or ground-truth file cannot be read.
    """
    results = load_results(run_dirs, registry=registry)
    tables = report_tables(results, n_boot=n_boot, seed=seed)
    if out is None:
        return Report(results, tables)
    files = write_report(results, tables, Path(out), gallery_size=gallery_size)
    return Report(results, tables, files)


def chart_pngs(tables: dict[str, pd.DataFrame]) -> dict[str, bytes]:
    """The report's charts as PNG bytes, keyed by title."""
    order = tables["leaderboard"]["run"].tolist()
    return {
        "Leaderboards": ch.leaderboards(tables["leaderboard"], tables["bootstrap"]),
        "Accuracy vs horizon": ch.accuracy_vs_horizon(tables["accuracy"], order),
        "Stasis index": ch.stasis(tables["stasis"]),
        "Q3 tolerance curve": ch.tolerance(tables["tolerance"]),
    }


def write_report(
    results: Results, tables: dict[str, pd.DataFrame], out: Path, *, gallery_size: int = 8
) -> dict[str, Path]:
    """Write charts, gallery images, CSV/Parquet exports and ``report.html`` under ``out``."""
    files: dict[str, Path] = {}
    for sub in ("charts", "gallery", "tables"):
        (out / sub).mkdir(parents=True, exist_ok=True)
    pngs = chart_pngs(tables)
    for title, png in pngs.items():
        files[f"chart:{title}"] = _write(out / "charts" / f"{_slug(title)}.png", png)
    datasets = {run.label: run.dataset for run in results.runs}
    cases = gallery.build_cases(results.units, datasets, gallery_size)
    for i, case in enumerate(cases):
        name = f"{i:02d}_{_slug(case.run)}_{case.scene_id}.png"
        files[f"gallery:{i}"] = _write(out / "gallery" / name, case.png)
    for name, frame in tables.items():
        files[f"table:{name}"] = out / "tables" / f"{name}.csv"
        frame.to_csv(files[f"table:{name}"], index=False)
    files.update(_export_frames(results, out))
    page = html.render(
        title="BilliardPhys-Bench report",
        runs=results.runs,
        headline=[("Leaderboard (strict)", _headline(tables))],
        sections=_sections(tables),
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


def _headline(tables: dict[str, pd.DataFrame]) -> str:
    board = tables["summary"].copy()
    ci = tables["bootstrap"].pivot_table(
        index="run", columns="metric", values=["lo", "hi"], observed=True
    )
    if not ci.empty:
        lo, hi = ci["lo"]["total"], ci["hi"]["total"]
        board["total 95% CI"] = [
            f"{100 * lo.get(r, float('nan')):.1f}–{100 * hi.get(r, float('nan')):.1f}%"
            for r in board["run"]
        ]
    note = (
        "<p class='muted'>Mean accuracy over horizons. Strict view: a missing answer, API error "
        "or parse error is wrong. <i>total_answered</i> leaves out calls that never returned "
        "an answer; <i>completeness</i> is the share answered. Baselines are floors "
        "(stasis, straight, random) and the ceiling (oracle).</p>"
    )
    return note + html.table(board, percent=SCORES)


SCORES = ("q1", "q2", "q3", "total", "total_answered", "completeness")


def _sections(tables: dict[str, pd.DataFrame]) -> list[tuple[str, str]]:
    pairs = tables["pairs"]
    horizons = [c for c in tables["by_horizon"].columns if c.startswith("h") or c == "mean"]
    stasis = ("contact_stasis", "q1_stasis", "q2_stasis", "motion_stasis")
    return [
        ("Accuracy by horizon (strict)", html.table(tables["by_horizon"], percent=horizons)),
        (
            "Accuracy by horizon (answered only)",
            html.table(tables["by_horizon_answered"], percent=horizons),
        ),
        (
            "Leaderboard on stable scenes",
            html.table(
                tables["leaderboard_stable"],
                percent=SCORES,
                empty="no stable scenes (the dataset has no stability annotation?)",
            ),
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
        ("Stasis index", html.table(tables["stasis"], percent=stasis)),
        (
            "Q1 and per-wall confusion",
            html.table(tables["confusion"], percent=("precision", "recall", "f1")),
        ),
        ("Q3 distance error (m)", html.table(tables["distance"])),
        ("Q3 distance error by horizon (m)", html.table(tables["distance_by_horizon"])),
        ("Tokens, cost, latency, retries", html.table(tables["usage"])),
    ]
