"""The summary table printed at the end of ``bpb run`` (scores from bpb_core.results)."""

from __future__ import annotations

from pathlib import Path


def show_summary(run_dirs: list[Path]) -> None:
    """Write ``scores.csv`` into each run folder and print the leaderboard summary."""
    from rich.table import Table

    from bpb_core.cli.console import stderr, stdout
    from bpb_core.errors import BpbError
    from bpb_core.runner.plan import write_scores

    try:
        frame = write_scores(run_dirs)
    except BpbError as exc:
        stderr().print(f"[yellow]warning:[/] could not score the run: {exc}")
        return
    if frame is None or frame.empty:
        return
    columns = [c for c in ("adapter", "q1", "q2", "q3", "total", "completeness") if c in frame]
    table = Table(*columns, title="bpb run: scores (strict; completeness = answered share)")
    for _, row in frame.iterrows():
        table.add_row(
            *(f"{row[c]:.3f}" if isinstance(row[c], float) else str(row[c]) for c in columns)
        )
    stdout().print(table)
    parents = sorted({str(d.parent) for d in run_dirs})
    where = " ".join(parents) if parents else "RUN_DIR"
    stderr().print(
        f"next: bpb report {where} --out {parents[0] if parents else '.'}/report "
        "(charts, failure gallery, HTML)",
        highlight=False,
    )
