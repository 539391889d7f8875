"""``bpb report RUN_DIR... [--out DIR] [--json]``: compare runs in the terminal, write a report;
``bpb view``: browse them in a local web app on 127.0.0.1 (see :mod:`bpb_core.web`).

A thin wrapper over :func:`bpb_core.report.build.build_report`; this module only renders tables.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
from rich.markup import escape

from bpb_core.cli.console import (
    PATH,
    PORT_HELP,
    PORTS,
    FiniteFloat,
    Name,
    counted,
    load_registry,
    pct,
    print_fitted,
    stderr,
    stdout,
)

if TYPE_CHECKING:
    import pandas as pd

    from bpb_core.report.build import Report, ReportPart
    from bpb_core.report.sections import Cell, Rows


USAGE_COLUMNS = {
    "calls": "calls",
    "input_tokens": "in tok",
    "output_tokens": "out tok",
    "reasoning_tokens": "reason tok",
    "cost": "cost $",
    "latency_mean": "latency ms",
    "retries": "retries",
    "parse_error": "parse err",
    "refused": "refused",
    "cut": "cut",
    "empty": "empty",
    "api_error": "api err",
    "missing": "missing",
}


@click.command("report")
@click.argument("run_dirs", nargs=-1, required=True, type=PATH)
@click.option("--out", type=PATH, help="Write charts, CSV/Parquet and report.html here.")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON (for scripts).")
@counted("--bootstrap", "n_boot", default=2000, low=10, help="Bootstrap resamples.")
@click.option("--seed", default=0, show_default=True, help="Bootstrap seed.")
@click.option(
    "--min-complete",
    default=0.9,
    show_default=True,
    type=FiniteFloat(0, 1),
    help="Share of a (run, task, horizon) cell that must be answered for it to count.",
)
@click.option(
    "--include-incomplete",
    is_flag=True,
    help="Keep tasks with a cell under --min-complete in the leaderboards (still marked).",
)
@counted("--gallery", "gallery_size", default=8, low=0, help="Failure gallery size.")
def report(
    run_dirs: tuple[Path, ...],
    out: Path | None,
    as_json: bool,
    n_boot: int,
    seed: int,
    min_complete: float,
    include_incomplete: bool,
    gallery_size: int,
) -> None:
    """Score run folders (or folders of run folders) and compare them.

    Prints, per dataset (runs on different datasets are never ranked together), the leaderboard
    (answered-only scores and completeness first, the strict score beside, bootstrap 95%
    intervals), accuracy by horizon with each cell's completeness, the diagnostics and usage.
    A task with a (task, horizon) cell under --min-complete answered is left out of the
    leaderboards. With --out, also writes PNG charts, CSV, Parquet, Markdown and LaTeX exports
    and one self-contained report.html with a failure gallery.
    """
    import warnings

    from bpb_core.report.build import Completeness, build_report
    from bpb_core.results.reading import DuplicateRunWarning, StrayAnswerWarning

    told = (DuplicateRunWarning, StrayAnswerWarning)
    rule = Completeness(min_complete, include_incomplete)
    with warnings.catch_warnings(record=True) as caught:
        for told_one in told:
            warnings.simplefilter("always", told_one)
        built = build_report(
            run_dirs, out, n_boot=n_boot, seed=seed, gallery_size=gallery_size,
            registry=load_registry(), completeness=rule,
        )  # fmt: skip
    # a run given twice is counted once, stray answer files are left out: one line says so
    for caught_one in caught:
        message, category = caught_one.message, caught_one.category
        if issubclass(category, told):
            line = f"[yellow]warning:[/] {escape(str(message))}"
            stderr().print(line, highlight=False, soft_wrap=True)
        else:
            warnings.showwarning(message, category, caught_one.filename, caught_one.lineno)
    if as_json:
        click.echo(json.dumps(built.summary_json(), indent=2, default=str))
        return
    _print_tables(built)
    if out is not None:
        stderr().print(f"wrote {built.files['html']} and {len(built.files) - 1} more files")


def _print_tables(built: Report) -> None:
    console = stdout()
    several = len(built.parts) > 1
    if several:
        datasets = len({part.dataset for part in built.parts})
        what = f"{datasets} datasets" if datasets > 1 else "one dataset"
        if any(part.scenes for part in built.parts):
            what += f" in {len(built.parts)} different sets of scenes"
        stderr().print(
            f"[yellow]note:[/] the runs answered {what}; each is reported on its own, never "
            "ranked together",
            highlight=False,
        )
        for part in built.parts:
            runs = ", ".join(run.label for run in part.results.runs)
            stderr().print(f"  {escape(part.title)}: {escape(runs)}", highlight=False)
    for part in built.parts:
        if several:
            console.rule(f"dataset {escape(part.title)}")
        _print_part(part, built)


def _print_part(part: ReportPart, built: Report) -> None:
    from bpb_core.report.sections import (
        REFERENCE_NOTE,
        different_conditions_note,
        different_scenes_note,
        epoch_columns,
        headline_cells,
        horizon_cells,
        reference_cells,
        reference_sources,
    )
    from bpb_core.results.tables import warning_lines

    tables, rule, console = part.tables, built.completeness, stdout()
    title = "Leaderboard (answered only, strict beside; mean over horizons)"
    _cell_table(title, *headline_cells(part, rule))
    if not tables["references"].empty:
        _cell_table("Published figures beside your runs", *reference_cells(part))
        for line in [REFERENCE_NOTE, *reference_sources(part)]:
            console.print(escape(line), highlight=False, style="dim")
    for run, line in warning_lines(part.results):
        console.print(f"[yellow]{escape(run)}: {escape(line)}[/]", highlight=False)
    for different in (different_scenes_note(part), different_conditions_note(part)):
        if different:
            console.print(f"[yellow]{escape(different)}[/]", highlight=False)
    if not part.results.units["baseline"].any():
        console.print(
            "[yellow]no baseline ran on this dataset: add the floors with bpb run --adapter "
            "baseline:stasis --adapter baseline:straight (offline, free)[/]", highlight=False,
        )  # fmt: skip
    for task, notes in part.metric_notes.items():
        table = tables[f"{task}_metrics"]
        frame = table[["run", "baseline", "complete", *epoch_columns(table), *notes]]
        title = f"{task} metrics beside accuracy (answered only)"
        _frame_table(title, frame, percent=True)
        for name, note in notes.items():
            console.print(f"[dim]{escape(name)}: {escape(note)}[/]", highlight=False)
    horizon = horizon_cells(tables["accuracy_answered"], rule)
    _cell_table("Accuracy by horizon (answered only; \\[answered share])", *horizon)
    if not tables["metadata"].empty:
        from bpb_core.results.tables import metadata_by_horizon

        wide = metadata_by_horizon(tables["metadata"])
        _frame_table("Adapters' own measurements by horizon", wide, percent=False)
    if part.results.suites:
        _stable_table(tables, part.results.suites[0].name)
        console.print(_exclusions(tables["stable_exclusions"]))
    for diagnostic in part.diagnostics:
        if diagnostic.terminal:
            table = tables[diagnostic.name]
            shown = ["complete"] if "complete" in table.columns else []
            shown += epoch_columns(table)
            frame = table[["run", "baseline", *shown, *diagnostic.terminal]]
            percent = (*diagnostic.percent, "complete")
            _frame_table(diagnostic.title, frame, percent=percent)
    use = tables["usage"].assign(latency_mean=lambda f: (1000 * f["latency_mean"]).round(0))
    use = use.rename(columns=USAGE_COLUMNS)[["run", "baseline", *USAGE_COLUMNS.values()]]
    _frame_table("Usage", use, percent=False)


def _cell_table(title: str, head: list[str], rows: Rows) -> None:
    """Print a table of report cells: partial cells carry their answered share in brackets,
    short ones are dim."""
    keys = int(head[1:2] == ["task"])
    fitted = [(_name(cells[0].text, b), [_cell_text(c) for c in cells[1:]]) for b, cells in rows]
    print_fitted(stdout(), title, head, fitted, keys=keys)


def _cell_text(cell: Cell) -> str:
    text = escape(cell.text) + (escape(f" [{cell.note}]") if cell.note else "")
    if cell.css == "short":
        return f"[dim]{text}[/]"
    return f"[yellow]{text}[/]" if cell.css == "partial" else text


def _frame_table(title: str, frame: pd.DataFrame, *, percent: bool | Sequence[str]) -> None:
    """Print a table of ``frame``; ``percent`` is True (every float column), False, or the
    columns shown as percentages."""
    columns = [c for c in frame.columns if c not in ("baseline", "run")]
    rows = [
        (
            _name(str(row["run"]), bool(row.get("baseline", False))),
            [
                _cell(row[c], percent is True or (percent is not False and c in percent))
                for c in columns
            ],
        )
        for row in frame.to_dict(orient="records")
    ]
    head = ["run", *map(str, columns)]
    print_fitted(stdout(), title, head, rows, keys=int(columns[:1] == ["task"]))


def _stable_table(tables: dict[str, pd.DataFrame], suite: str) -> None:
    head = ["run", f"{suite}, all", f"{suite}, stable", "stable scene-tasks"]
    stable = {str(r["run"]): r for r in tables["leaderboard_stable"].to_dict(orient="records")}
    rows = []
    for row in tables["leaderboard"].to_dict(orient="records"):
        kept = stable.get(str(row["run"]))
        cells = [
            pct(row[suite]),
            "–" if kept is None else pct(kept[suite]),
            "0" if kept is None else _scene_tasks(kept),
        ]
        rows.append((_name(str(row["run"]), bool(row["baseline"])), cells))
    print_fitted(stdout(), f"All scenes vs the stable subset (strict {suite})", head, rows)


def _scene_tasks(row: Mapping[Any, Any]) -> str:
    """A count of scene-tasks, with how many times each was asked when more than once."""
    epochs = int(row["epochs"])
    return str(row["expected"]) + (f" (x{epochs} epochs)" if epochs > 1 else "")


def _exclusions(frame: pd.DataFrame) -> str:
    """One line: how many scenes each stability reason leaves out of the stable subset."""
    parts = [f"{r['reason']} {r['scenes']}" for r in frame.to_dict(orient="records")]
    return "Scenes left out of the stable subset: " + ", ".join(parts)


def _name(run: str, baseline: bool) -> Name:
    """``run``'s name cell (baselines dim; run names carry option sets: [effort=high])."""
    return Name(run, " (baseline)", "dim") if baseline else Name(run)


def _cell(value: Any, percent: bool) -> str:
    if isinstance(value, float):
        if math.isnan(value):
            return "–"
        return pct(value) if percent else f"{value:.3g}"
    return escape(str(value))


@click.command("view")
@click.argument("run_dirs", nargs=-1, required=True, type=PATH)
@click.option("--port", default=8766, show_default=True, type=PORTS, help=PORT_HELP)
def view(run_dirs: tuple[Path, ...], port: int) -> None:
    """Browse runs pair by pair: image, exact prompt, every attempt, verdicts."""
    from bpb_core.web import listen, require_web, serve, url

    require_web()
    from bpb_core.web.viewer import Viewer, viewer_app

    sock = listen(port)
    viewer = Viewer.load(list(run_dirs), load_registry())
    stderr().print(f"bpb view: open {url(sock)} (Ctrl-C stops)")
    serve(viewer_app(viewer), sock)
