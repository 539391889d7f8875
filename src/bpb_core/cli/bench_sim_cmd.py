"""``bpb bench sim``: simulators side by side (speed, error against mpmath, label disagreements)."""

from __future__ import annotations

from pathlib import Path

import click


@click.command("sim")
@click.option("--scenes", default=100, show_default=True, help="Random scenes to compare on.")
@click.option("--seed", default=0, show_default=True, help="Seed of the random scenes.")
@click.option("--dts", default="1e-2,1e-3,1e-4", show_default=True, help="pymunk time steps.")
@click.option(
    "--simulate-scenes",
    default=1000,
    show_default=True,
    help="Scene files for the `bpb simulate` timing (0 skips it).",
)
@click.option("--plot", type=click.Path(path_type=Path), default=None, help="Write the PNG here.")
@click.option(
    "--markdown",
    type=click.Path(path_type=Path),
    default=None,
    help="Update the simulator section of this benchmarks.md.",
)
def sim(
    scenes: int, seed: int, dts: str, simulate_scenes: int, plot: Path | None, markdown: Path | None
) -> None:
    """Time analytic and pymunk (several dt) on the same scenes against the mpmath reference."""
    from rich.progress import Progress
    from rich.table import Table

    from bpb_core.cli.console import stderr, stdout
    from bpb_core.errors import BadInput
    from bpb_tasks.simulators import bench, bench_report

    try:
        steps = [float(x) for x in dts.split(",") if x.strip()]
    except ValueError:
        raise BadInput(f"--dts: expected comma-separated numbers, got {dts!r}") from None
    with Progress(console=stderr(), transient=True) as bar:
        task = bar.add_task("simulating", total=scenes)
        result = bench.bench_simulators(
            scenes, seed, steps, progress=lambda _l, done, _t: bar.update(task, completed=done)
        )
    if simulate_scenes > 0:
        result = bench.with_simulate_timing(result, simulate_scenes)
    table = Table(title=f"bpb bench sim: {result.scenes} scenes, {result.machine}, {result.day}")
    headers = ("simulator", "ms/scene", "max err m", "median err m", "Q1", "Q2", "pocket", "Q3")
    for column in headers:
        first = column == "simulator"
        table.add_column(column, justify="left" if first else "right", no_wrap=first)
    for row in result.rows:
        table.add_row(
            row.name,
            f"{row.ms_per_scene:.3g}",
            f"{row.max_error:.1e}",
            f"{row.median_error:.1e}",
            str(row.q1_disagree),
            str(row.q2_disagree),
            str(row.pocket_disagree),
            str(row.q3_wrong),
        )
    stdout().print(table)
    if result.simulate_ms is not None:
        for label, ms in result.simulate_ms.items():
            stdout().print(f"bpb simulate, {label}: {ms:.3f} ms/scene")
    if plot is not None:
        bench_report.plot(result, plot)
    if markdown is not None:
        rel = None if plot is None else _relative(plot, markdown.parent)
        bench_report.update_section(markdown, bench_report.markdown(result, rel))


def _relative(path: Path, base: Path) -> str:
    try:
        return str(path.resolve().relative_to(base.resolve()))
    except ValueError:
        return str(path)
