"""``bpb bench score``."""

from __future__ import annotations

import click

from bpb_core.cli.console import stdout


@click.command("score")
@click.option("--rows", default=1_000_000, show_default=True, help="Answer rows per scorer.")
@click.option("--repeats", default=5, show_default=True, help="Timed repeats (best and median).")
@click.option("--loop-rows", default=50_000, show_default=True, help="Rows for the per-row loop.")
@click.option(
    "--runs", "run_dirs", multiple=True, help="Also time reading and scoring these run folders."
)
def bench_score_cmd(rows: int, repeats: int, loop_rows: int, run_dirs: tuple[str, ...]) -> None:
    """Time the vectorised scorers beside a per-row loop (target: 1M rows in at most 2 s)."""
    from rich.table import Table

    from bpb_core.bench.score import TARGET_SECONDS, bench_score

    timings = bench_score(rows, repeats=repeats, loop_rows=loop_rows)
    table = Table(
        "task", "method", "rows", "best s", "median s", "rows/s",
        title=f"Scoring speed (target: {rows:,} rows in at most {TARGET_SECONDS:g} s)",
    )  # fmt: skip
    for t in timings:
        table.add_row(
            t.task, t.method, f"{t.rows:,}", f"{t.best:.3f}", f"{t.median:.3f}",
            f"{t.rows_per_second:,.0f}",
        )  # fmt: skip
    stdout().print(table)
    if run_dirs:
        from bpb_core.bench.score import bench_load

        load = bench_load(list(run_dirs))
        stdout().print(
            f"load_results: {load.answers:,} answer files, {load.units:,} units: "
            f"{load.cold:.2f} s cold, {load.warm:.2f} s warm "
            f"({load.answers / load.cold:,.0f} files/s cold)"
        )
    slow = [t for t in timings if t.method == "vectorised" and t.best > TARGET_SECONDS]
    if slow:
        raise click.exceptions.Exit(1)
