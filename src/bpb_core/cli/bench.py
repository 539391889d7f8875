"""``bpb bench``: ``bpb bench sim``, simulators side by side (speed, error against a reference,
disagreements). The other benchmarks are scripts in the checkout's ``benchmarks/`` folder."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from bpb_core.cli.console import PATH, load_registry, stderr, stdout

if TYPE_CHECKING:
    from bpb_core.bench.sim_report import SimBench


@click.group("bench")
def bench() -> None:
    """Benchmarks: simulators side by side, speed against error (more in benchmarks/)."""


@bench.command("sim")
@click.option("--scenes", default=100, show_default=True, help="Scenes to compare on.")
@click.option("--seed", default=0, show_default=True, help="Seed of the scenes.")
@click.option("--family", default=None, help="Scene family [default: the default family].")
@click.option(
    "--contestant",
    "contestants",
    multiple=True,
    help="Simulator as NAME or NAME:KEY=VALUE,... such as NAME:dt=0.01 (repeatable) "
    "[default: the family's list].",
)
@click.option("--reference", default=None, help="Reference simulator [default: the family's].")
@click.option(
    "--simulate-scenes",
    default=1000,
    show_default=True,
    help="Scene files for the `bpb simulate` timing (0 skips it).",
)
@click.option(
    "--simulate-with", multiple=True, help="Simulator timed through `bpb simulate` (repeatable) "
    "[default: the first contestant].",
)  # fmt: skip
@click.option(
    "--reference-scenes",
    type=int,
    default=None,
    help="Run the reference on the first N scenes only [default: all].",
)
@click.option(
    "--scaling",
    "scaling",
    multiple=True,
    help="Simulator to time against events per scene on scenes made busier x1..x32 "
    "(repeatable; the family must count events).",
)
@click.option("--scaling-scenes", default=200, show_default=True, help="Scenes for --scaling.")
@click.option("--plot", type=PATH, help="Write the PNG here.")
@click.option("--markdown", type=PATH, help="Update the simulator section of this benchmarks.md.")
def bench_sim(
    scenes: int,
    seed: int,
    family: str | None,
    contestants: tuple[str, ...],
    reference: str | None,
    simulate_scenes: int,
    simulate_with: tuple[str, ...],
    reference_scenes: int | None,
    scaling: tuple[str, ...],
    scaling_scenes: int,
    plot: Path | None,
    markdown: Path | None,
) -> None:
    """Time simulators of one scene family on the same scenes and compare with a reference.

    Exits 1 when a simulator failed on a scene (left out of its figures)."""
    from rich.progress import Progress

    from bpb_core.bench import sim_report
    from bpb_core.bench.sim import (
        bench_simulators,
        check_simulate_with,
        scaling_simulators,
        with_scaling,
        with_simulate_timing,
    )
    from bpb_core.errors import BadInput

    if plot is not None:  # before the bench: a path that cannot be written would lose it
        from bpb_core.layout import check_writable_file

        check_writable_file(plot, "--plot")
    if markdown is not None:
        sim_report.check_section_file(markdown)
    registry = load_registry()
    name = family or registry.default_family()  # refuse bad options of the later steps first
    if scaling:
        scaling_simulators(registry, name, scaling, scaling_scenes)
    if simulate_scenes < 0:
        raise BadInput(f"--simulate-scenes: must be at least 0 (0 skips), got {simulate_scenes}")
    if simulate_scenes and simulate_with:
        check_simulate_with(registry, name, simulate_with)
    with Progress(console=stderr(), transient=True) as bar:
        task = bar.add_task("simulating", total=scenes)
        result = bench_simulators(
            scenes,
            seed,
            contestants,
            reference,
            family=family,
            registry=registry,
            progress=lambda done, _total: bar.update(task, completed=done),
            reference_scenes=reference_scenes,
        )
    if scaling:
        result = with_scaling(result, scaling, scaling_scenes, registry=registry)
    if simulate_scenes > 0:
        others = [r.name for r in result.rows if not r.reference]
        timed = list(simulate_with) or [(others or [result.rows[0].name])[0]]
        result = with_simulate_timing(result, simulate_scenes, timed, registry)
    _show(result)
    if plot is not None:
        sim_report.plot(result, plot)
    if markdown is not None:
        rel = None if plot is None else _relative(plot, markdown.parent)
        sim_report.update_section(markdown, sim_report.markdown(result, rel))
    if any(row.failed for row in result.rows) or any(s.failed for s in result.scaling):
        raise click.exceptions.Exit(1)  # figures written; a contestant failed on some scenes


def _show(result: SimBench) -> None:
    from rich.table import Table

    from bpb_core.bench.sim_report import count_cell, figure, row_name

    title = f"bpb bench sim: {result.scenes} {result.family} scenes, {result.machine}, {result.day}"
    table = Table(title=title)
    failed = ["failed"] if any(row.failed for row in result.rows) else []
    for column in ("simulator", "ms/scene", "max error", "median error", *result.columns, *failed):
        first = column == "simulator"
        table.add_column(column, justify="left" if first else "right", no_wrap=first)
    for row in result.rows:
        cells = [figure(row.ms_per_scene), figure(row.max_error, ".1e")]
        cells += [figure(row.median_error, ".1e")]
        cells += [count_cell(row, c) for c in result.columns] + [str(row.failed)] * len(failed)
        table.add_row(row_name(row), *cells)
    stdout().print(table)
    for row in result.rows:
        if row.failed:
            stderr().print(
                f"warning: {row.name}: failed on {row.failed} scene(s), left out of its "
                f"figures; first: {row.first_error}",
                markup=False,
            )
    for row in result.rows:
        if row.us_per_event is not None or row.batch_ms is not None:
            batch = "–" if row.batch_ms is None else f"{row.batch_ms:.3g}"
            per_event = "–" if row.us_per_event is None else f"{row.us_per_event:.3g}"
            stdout().print(f"{row.name}: {per_event} µs/event, batch {batch} ms/scene")
    for s in result.scaling:
        lost = f", failed on {s.failed} scene(s)" if s.failed else ""
        stdout().print(
            f"x{s.factor:g} {s.name}: {figure(s.events_per_scene)} events/scene, "
            f"{figure(s.ms_per_scene)} ms/scene, {figure(s.us_per_event)} µs/event{lost}"
        )
    # one warning per --scaling simulator that failed on scaled scenes
    for name in dict.fromkeys(s.name for s in result.scaling if s.failed):
        rows = [s for s in result.scaling if s.name == name and s.failed]
        where = ", ".join(f"x{s.factor:g}: {s.failed}" for s in rows)
        stderr().print(
            f"warning: --scaling {name}: failed on {sum(s.failed for s in rows)} scaled "
            f"scene(s) ({where}), left out of its figures; first: {rows[0].first_error}",
            markup=False,
        )
    for label, ms in (result.simulate_ms or {}).items():
        stdout().print(f"bpb simulate ({result.simulate_with}), {label}: {ms:.3f} ms/scene")


def _relative(path: Path, base: Path) -> str:
    try:
        return str(path.resolve().relative_to(base.resolve()))
    except ValueError:
        return str(path)
