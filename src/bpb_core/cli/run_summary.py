"""The summary table printed at the end of ``bpb run`` (scores from bpb_core.results)."""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import pandas as pd
    from rich.table import Table

    from bpb_core.dataset.reader import DataFolder
    from bpb_core.registry import Registry

_NOT_SCORES = (
    "run", "adapter", "model", "baseline", "expected", "epochs", "completeness", "worst_cell",
)  # fmt: skip


def show_summary(
    run_dirs: list[Path], registry: Registry, folders: Iterable[DataFolder] = ()
) -> None:
    """Write ``scores.csv`` into each run folder and print the leaderboard summary
    (``folders``: the runs' datasets, already read)."""
    from rich.markup import escape

    from bpb_core.cli.console import stderr, stdout
    from bpb_core.errors import BpbError
    from bpb_core.results.frames import write_scores

    try:
        frame = write_scores(run_dirs, registry, folders)
    except BpbError as exc:
        stderr().print(f"[yellow]warning:[/] could not score the run: {exc}")
        return
    if frame is None or frame.empty:
        return
    stdout().print(_table(frame))
    for run, line in frame.attrs.get("incomplete", {}).items():
        stderr().print(f"[yellow]{escape(run)}: {escape(line)}[/]", highlight=False)
    parents = sorted({str(d.parent) for d in run_dirs})
    where = " ".join(parents) if parents else "RUN_DIR"
    stderr().print(
        f"next: bpb report {where} --out {parents[0] if parents else '.'}/report "
        "(charts, failure gallery, HTML)",
        highlight=False,
    )


def _table(frame: pd.DataFrame) -> Table:
    """Answered-only scores and completeness first, the strict score beside each."""
    from rich.markup import escape
    from rich.table import Table

    names = [
        c for c in frame.columns
        if c not in _NOT_SCORES and c != "short" and not c.endswith("_answered")
    ]  # fmt: skip
    table = Table(title="bpb run: scores (answered only; strict in brackets)")
    for column in ("adapter", "complete", *names, "left out"):
        table.add_column(column, justify="left" if column == "adapter" else "right")
    for _, row in frame.iterrows():
        cells = [escape(str(row["adapter"])), _pct(row["completeness"])]
        for name in names:
            answered, strict = row[f"{name}_answered"], row[name]
            if not math.isnan(float(answered)):
                cells.append(f"{_pct(answered)} ({_pct(strict)})")
            else:  # too incomplete, or not asked (a suite with a task the run lacks)
                cells.append("left out" if row["short"] else "–")
        cells.append(escape(str(row["short"])) or "–")
        table.add_row(*cells)
    return table


def _pct(value: float) -> str:
    return "–" if math.isnan(float(value)) else f"{100 * value:.1f}%"
