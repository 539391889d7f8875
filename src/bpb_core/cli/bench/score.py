"""``bpb bench score``: scoring speed of every installed scorer on real answers."""

from __future__ import annotations

import click


@click.command("score")
@click.option(
    "--rows", default=1_000_000, show_default=True, help="Unit rows per scorer (at most 20M)."
)
@click.option(
    "--repeats", default=5, show_default=True, help="Timed repeats, at most 100 (best and median)."
)
@click.option(
    "--per-horizon",
    default=20,
    show_default=True,
    help="Scenes per horizon of the dataset the answers are about (x5 horizons; at most 100,000).",
)
@click.option(
    "--runs", "run_dirs", multiple=True, help="Also time reading and scoring these run folders."
)
def bench_score(rows: int, repeats: int, per_horizon: int, run_dirs: tuple[str, ...]) -> None:
    """Time each scorer on real units (target: 1M rows in at most 2 s); exit 1 when slower."""
    from rich.table import Table

    from bpb_core.bench import MAX_REPEATS
    from bpb_core.bench.score import MAX_ROWS, TARGET_SECONDS, bench_score
    from bpb_core.cli.console import load_registry, stderr, stdout
    from bpb_core.dataset.jobs import check_per_horizon
    from bpb_core.errors import BadInput

    if rows < 1 or repeats < 1:
        raise BadInput("--rows/--repeats: must be at least 1")
    if rows > MAX_ROWS:  # the units are tiled to --rows and held in memory at once
        raise BadInput(f"--rows: at most {MAX_ROWS:,} (about 3 GB of units), got {rows:,}")
    if repeats > MAX_REPEATS:  # each repeat scores --rows units for every task
        raise BadInput(f"--repeats: at most {MAX_REPEATS}, got {repeats:,}")
    check_per_horizon(per_horizon)
    registry = load_registry()
    if run_dirs:  # a bad folder is refused now, not after the scoring benchmark
        from bpb_core.results.reading import find_runs

        find_runs(list(run_dirs), registry)
    with stderr().status("scoring") as status:
        timings = bench_score(
            rows, repeats=repeats, per_horizon=per_horizon, registry=registry,
            progress=lambda what: status.update(what),
        )  # fmt: skip
    table = Table(
        "task", "method", "rows", "best s", "median s", "rows/s", "correct",
        title=f"Scoring speed (target: {rows:,} rows in at most {TARGET_SECONDS:g} s)",
    )  # fmt: skip
    for t in timings:
        share = "" if t.correct is None else f"{100 * t.correct:.1f}%"
        table.add_row(
            t.task, t.method, f"{t.rows:,}", f"{t.best:.3f}", f"{t.median:.3f}",
            f"{t.rows_per_second:,.0f}", share,
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
