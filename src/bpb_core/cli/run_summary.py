"""The summary table printed at the end of ``bpb run`` (scores from bpb_core.results)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from bpb_core.registry import Registry

_NOT_SCORES = ("run", "adapter", "model", "baseline", "expected")


def show_summary(run_dirs: list[Path], registry: Registry) -> None:
    """Write ``scores.csv`` into each run folder and print the leaderboard summary."""
    from rich.markup import escape
    from rich.table import Table

    from bpb_core.cli.console import stderr, stdout
    from bpb_core.errors import BpbError
    from bpb_core.results.scores_csv import write_scores

    try:
        frame = write_scores(run_dirs, registry)
    except BpbError as exc:
        stderr().print(f"[yellow]warning:[/] could not score the run: {exc}")
        return
    if frame is None or frame.empty:
        return
    scores = [c for c in frame.columns if c not in _NOT_SCORES and not c.endswith("_answered")]
    columns = ["adapter", *scores]
    table = Table(*columns, title="bpb run: scores (strict; completeness = answered share)")
    for _, row in frame.iterrows():
        table.add_row(
            *(
                f"{row[c]:.3f}" if isinstance(row[c], float) else escape(str(row[c]))
                for c in columns
            )
        )
    stdout().print(table)
    parents = sorted({str(d.parent) for d in run_dirs})
    where = " ".join(parents) if parents else "RUN_DIR"
    stderr().print(
        f"next: bpb report {where} --out {parents[0] if parents else '.'}/report "
        "(charts, failure gallery, HTML)",
        highlight=False,
    )
