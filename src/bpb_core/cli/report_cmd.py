"""``bpb report RUN_DIR... [--out DIR] [--json]``: compare runs in the terminal, write a report.

A thin wrapper over :func:`bpb_core.report.build.build_report`; this module only renders tables.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from bpb_core.cli.console import load_registry, stderr, stdout

if TYPE_CHECKING:
    import pandas as pd
    from rich.table import Table

    from bpb_core.report.build import Report


USAGE_COLUMNS = {
    "calls": "calls",
    "input_tokens": "in tok",
    "output_tokens": "out tok",
    "reasoning_tokens": "reason tok",
    "cost": "cost $",
    "latency_mean": "latency s",
    "retries": "retries",
    "parse_error": "parse err",
    "api_error": "api err",
    "missing": "missing",
}


@click.command("report")
@click.argument("run_dirs", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option(
    "--out", type=click.Path(path_type=Path), help="Write charts, CSV/Parquet and report.html here."
)
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON (for scripts).")
@click.option(
    "--bootstrap",
    "n_boot",
    default=2000,
    show_default=True,
    type=click.IntRange(10),
    help="Bootstrap resamples.",
)
@click.option("--seed", default=0, show_default=True, help="Bootstrap seed.")
@click.option(
    "--gallery",
    "gallery_size",
    default=8,
    show_default=True,
    type=click.IntRange(0),
    help="Failure gallery size.",
)
def report(
    run_dirs: tuple[Path, ...],
    out: Path | None,
    as_json: bool,
    n_boot: int,
    seed: int,
    gallery_size: int,
) -> None:
    """Score run folders (or folders of run folders) and compare them.

    Prints the leaderboards (strict and answered-only, with bootstrap 95% intervals), accuracy by
    horizon, the stasis index and usage. With --out, also writes PNG charts, CSV and Parquet
    exports and one self-contained report.html with a failure gallery.
    """
    from bpb_core.report.build import build_report

    built = build_report(
        run_dirs, out, n_boot=n_boot, seed=seed, gallery_size=gallery_size,
        registry=load_registry(),
    )  # fmt: skip
    if as_json:
        click.echo(json.dumps(built.summary_json(), indent=2, default=str))
        return
    _print_tables(built)
    if out is not None:
        stderr().print(f"wrote {built.files['html']} and {len(built.files) - 1} more files")


def _print_tables(built: Report) -> None:
    tables, results = built.tables, built.results
    console = stdout()
    console.print(_leaderboard(tables["summary"], tables["bootstrap"], built))
    console.print(_frame_table("Accuracy by horizon (strict)", tables["by_horizon"], percent=True))
    if not tables["metadata"].empty:
        from bpb_core.results.metadata import metadata_by_horizon

        wide = metadata_by_horizon(tables["metadata"])
        console.print(_frame_table("Adapters' own measurements by horizon", wide, percent=False))
    if results.suites:
        console.print(_stable_table(tables, results.suites[0].name))
        console.print(_exclusions(tables["stable_exclusions"]))
    for diagnostic in built.diagnostics:
        if diagnostic.terminal:
            frame = tables[diagnostic.name][["run", "baseline", *diagnostic.terminal]]
            console.print(_frame_table(diagnostic.title, frame, percent=diagnostic.percent))
    use = tables["usage"].rename(columns=USAGE_COLUMNS)[
        ["run", "baseline", *USAGE_COLUMNS.values()]
    ]
    console.print(_frame_table("Usage", use, percent=False))


def _leaderboard(board: pd.DataFrame, ci: pd.DataFrame, built: Report) -> Table:
    from rich.table import Table

    from bpb_core.results.tables import metrics

    results = built.results
    scores = metrics(results.units, results.suites)
    first = results.suites[0].name if results.suites else None
    extra = ["95% CI", "answered-only"] if first else []
    table = Table(title="Leaderboard (mean over horizons; strict = missing/errors wrong)")
    for name in ("run", *scores, *extra, "complete"):
        table.add_column(name, justify="left" if name == "run" else "right", no_wrap=True)
    rows = ci[ci["metric"] == first]
    bounds = dict(zip(rows["run"], zip(rows["lo"], rows["hi"], strict=True), strict=True))
    for row in board.to_dict(orient="records"):
        run = str(row["run"])
        cells = [_pct(row[m]) for m in scores]
        if first:
            lo, hi = bounds.get(run, (math.nan, math.nan))
            interval = "–" if math.isnan(lo) else f"{_pct(lo)}–{_pct(hi)}"
            cells += [interval, _pct(row[f"{first}_answered"])]
        table.add_row(_name(run, bool(row["baseline"])), *cells, _pct(row["completeness"]))
    return table


def _frame_table(title: str, frame: pd.DataFrame, *, percent: bool | Sequence[str]) -> Table:
    """A rich table of ``frame``; ``percent`` is True (every float column), False, or the
    columns shown as percentages."""
    from rich.table import Table

    table = Table(title=title)
    columns = [c for c in frame.columns if c != "baseline"]
    for name in columns:
        left = name in ("run", "task")
        table.add_column(str(name), justify="left" if left else "right", no_wrap=name == "run")
    for row in frame.to_dict(orient="records"):
        cells = [
            _cell(row[c], percent is True or (percent is not False and c in percent))
            for c in columns
        ]
        cells[0] = _name(str(row["run"]), bool(row.get("baseline", False)))
        table.add_row(*cells)
    return table


def _stable_table(tables: dict[str, pd.DataFrame], suite: str) -> Table:
    from rich.table import Table

    table = Table(title=f"All scenes vs the stable subset (strict {suite})")
    for name in ("run", f"{suite}, all", f"{suite}, stable", "stable scene-tasks"):
        table.add_column(name, justify="left" if name == "run" else "right", no_wrap=True)
    stable = {str(r["run"]): r for r in tables["leaderboard_stable"].to_dict(orient="records")}
    for row in tables["leaderboard"].to_dict(orient="records"):
        run = str(row["run"])
        kept = stable.get(run)
        table.add_row(
            _name(run, bool(row["baseline"])),
            _pct(row[suite]),
            "–" if kept is None else _pct(kept[suite]),
            "0" if kept is None else str(kept["expected"]),
        )
    return table


def _exclusions(frame: pd.DataFrame) -> str:
    """One line: how many scenes each stability reason leaves out of the stable subset."""
    parts = [f"{r['reason']} {r['scenes']}" for r in frame.to_dict(orient="records")]
    return "Scenes left out of the stable subset: " + ", ".join(parts)


def _name(run: str, baseline: bool) -> str:
    from rich.markup import escape  # run names carry option sets in brackets: [effort=high]

    return f"[dim]{escape(run)} (baseline)[/]" if baseline else escape(run)


def _pct(value: Any) -> str:
    return (
        "–"
        if value is None or (isinstance(value, float) and math.isnan(value))
        else f"{100 * value:.1f}%"
    )


def _cell(value: Any, percent: bool) -> str:
    if isinstance(value, float):
        if math.isnan(value):
            return "–"
        return _pct(value) if percent else f"{value:.3g}"
    return str(value)
