"""``bpb bench run``: runner request rate against a bare litellm loop, and peak memory."""

from __future__ import annotations

import signal
from pathlib import Path
from typing import TYPE_CHECKING

import click

if TYPE_CHECKING:
    from rich.table import Table

    from bpb_core.bench.run import Phase


@click.command("run")
@click.option("--concurrency", type=click.IntRange(min=1), default=64, show_default=True)
@click.option("--latency", type=float, default=1.0, show_default=True, help="Server delay (s).")
@click.option(
    "--throughput-scenes",
    type=click.IntRange(min=1),
    default=43,
    show_default=True,
    help="Scenes per horizon for the rate phases (x5 horizons x the family's default tasks; "
    "at most 100,000).",
)
@click.option(
    "--memory-scenes",
    type=click.IntRange(min=0),
    default=200,
    show_default=True,
    help="Scenes per horizon for the memory run (200 -> 3,000 calls with 3 tasks; 0 skips; "
    "at most 100,000).",
)
@click.option(
    "--work",
    type=click.Path(path_type=Path),
    default=Path(".bpb-bench"),
    show_default=True,
    help="Where the bench dataset is generated (and reused).",
)
@click.option(
    "--rounds",
    type=click.IntRange(min=1),
    default=2,
    show_default=True,
    help="Alternating rounds of each client in the rate phases.",
)
def bench_run(
    concurrency: int,
    latency: float,
    throughput_scenes: int,
    memory_scenes: int,
    rounds: int,
    work: Path,
) -> None:
    """Request rate of `bpb run` vs a bare litellm.acompletion loop (server side), peak RSS.

    Exits 1 when a measured client failed."""
    from rich.table import Table

    from bpb_core.bench import machine_description, today
    from bpb_core.bench.run import bench_dataset, bench_memory, bench_throughput
    from bpb_core.bench.run_bare import CALL_TIMEOUT
    from bpb_core.cli.console import stderr, stdout
    from bpb_core.dataset.jobs import check_per_horizon
    from bpb_core.errors import BadInput
    from bpb_core.layout import check_writable_folder

    if not 0 <= latency < CALL_TIMEOUT:  # at or above it every call times out; nan too
        raise BadInput(
            f"--latency: must be at least 0 and below the clients' {CALL_TIMEOUT} s call "
            f"timeout, got {latency:g}"
        )
    check_per_horizon(throughput_scenes, "--throughput-scenes")
    check_per_horizon(memory_scenes, "--memory-scenes", least=0)
    check_writable_folder(work, "--work")
    # SIGTERM (a kill, a cancelled CI job) unwinds like Ctrl-C, so the fake server and the
    # client being measured are stopped instead of being left running
    signal.signal(signal.SIGTERM, _terminated)

    def generating(data: Path, scenes: int) -> None:
        stderr().print(f"generating {scenes} scenes with images in {data} ...")

    data = bench_dataset(work, max(throughput_scenes, memory_scenes), generating)
    bare, ours = bench_throughput(data, concurrency, latency, throughput_scenes, rounds)
    table = Table(
        "client", "requests", "seconds", "req/s", "% of ideal", "% of bare", "peak RSS MB", "exit",
        title=f"bpb bench run: {machine_description()}, {today()}, "
        f"concurrency {concurrency}, latency {latency:g} s",
    )  # fmt: skip
    ideal = concurrency / latency if latency > 0 else float("inf")
    table.add_row("ideal", "", "", f"{ideal:.1f}", "100.0", "", "", "")
    phases = [bare, ours]
    for phase in phases:
        _add(table, phase, ideal, bare)
    if memory_scenes:
        phases.append(bench_memory(data, memory_scenes, concurrency))
        _add(table, phases[-1], None, None)
    stdout().print(table)
    failed = [phase for phase in phases if phase.exit_code]
    for phase in failed:
        stderr().print(f"{phase.name} failed (exit {phase.exit_code}): {phase.error or '?'}")
    if failed:
        raise click.exceptions.Exit(1)  # a client failed: its figures do not count


def _terminated(signum: int, frame: object) -> None:
    raise SystemExit(128 + signum)


def _add(table: Table, phase: Phase, ideal: float | None, bare: Phase | None) -> None:
    """One client's row; a failed client's timings are not figures (shown as "–"), nor is a
    share of a failed bare loop."""
    if phase.exit_code:
        table.add_row(phase.name, str(phase.requests), *["–"] * 5, str(phase.exit_code))
        return

    def share(of: float | None) -> str:
        return f"{100 * phase.rate / of:.1f}" if of else ""

    base = None if bare is None else ("–" if bare.exit_code else share(bare.rate))
    table.add_row(
        phase.name, str(phase.requests), f"{phase.seconds:.2f}", f"{phase.rate:.1f}",
        share(ideal), base or "", f"{phase.peak_rss_mb:.0f}", str(phase.exit_code),
    )  # fmt: skip
