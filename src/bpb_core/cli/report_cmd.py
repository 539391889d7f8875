"""``bpb report RUN_DIR... [--out DIR] [--json]``: compare runs in the terminal, write a report.

A thin wrapper over :func:`bpb_core.report.build.build_report`; this module only renders tables.
"""

from __future__ import annotations

import json
import math
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
    tables = built.tables
    console = stdout()
    console.print(_leaderboard(tables["summary"], tables["bootstrap"]))
    console.print(_frame_table("Accuracy by horizon (strict)", tables["by_horizon"], percent=True))
    console.print(_stable_table(tables))
    stasis = tables["stasis"][
        ["run", "baseline", "contact_stasis", "motion_stasis", "contacts", "moved"]
    ]
    console.print(_frame_table("Stasis index (answered units)", stasis, percent=True))
    use = tables["usage"].rename(columns=USAGE_COLUMNS)[
        ["run", "baseline", *USAGE_COLUMNS.values()]
    ]
    console.print(_frame_table("Usage", use, percent=False))


def _leaderboard(board: pd.DataFrame, ci: pd.DataFrame) -> Table:
    from rich.table import Table

    table = Table(title="Leaderboard (mean over horizons; strict = missing/errors wrong)")
    for name in ("run", "q1", "q2", "q3", "total", "95% CI", "answered-only", "complete"):
        table.add_column(name, justify="left" if name == "run" else "right", no_wrap=True)
    rows = ci[ci["metric"] == "total"]
    bounds = dict(zip(rows["run"], zip(rows["lo"], rows["hi"], strict=True), strict=True))
    for row in board.to_dict(orient="records"):
        run = str(row["run"])
        interval = "–"
        lo, hi = bounds.get(run, (math.nan, math.nan))
        if not math.isnan(lo):
            interval = f"{_pct(lo)}–{_pct(hi)}"
        table.add_row(
            _name(run, bool(row["baseline"])),
            *(_pct(row[m]) for m in ("q1", "q2", "q3", "total")),
            interval, _pct(row["total_answered"]), _pct(row["completeness"]),
        )  # fmt: skip
    return table


def _frame_table(title: str, frame: pd.DataFrame, *, percent: bool) -> Table:
    from rich.table import Table

    table = Table(title=title)
    columns = [c for c in frame.columns if c != "baseline"]
    for name in columns:
        left = name in ("run", "task")
        table.add_column(str(name), justify="left" if left else "right", no_wrap=name == "run")
    for row in frame.to_dict(orient="records"):
        cells = [_cell(row[c], percent and c not in ("contacts", "moved")) for c in columns]
        cells[0] = _name(str(row["run"]), bool(row.get("baseline", False)))
        table.add_row(*cells)
    return table


def _stable_table(tables: dict[str, pd.DataFrame]) -> Table:
    from rich.table import Table

    table = Table(title="All scenes vs the stable subset (strict totals)")
    for name in ("run", "total, all", "total, stable", "stable scene-tasks"):
        table.add_column(name, justify="left" if name == "run" else "right", no_wrap=True)
    stable = {str(r["run"]): r for r in tables["leaderboard_stable"].to_dict(orient="records")}
    for row in tables["leaderboard"].to_dict(orient="records"):
        run = str(row["run"])
        kept = stable.get(run)
        table.add_row(
            _name(run, bool(row["baseline"])),
            _pct(row["total"]),
            "–" if kept is None else _pct(kept["total"]),
            "0" if kept is None else str(kept["expected"]),
        )
    return table


def _name(run: str, baseline: bool) -> str:
    return f"[dim]{run} (baseline)[/]" if baseline else run


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
