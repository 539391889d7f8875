"""``bpb bench run``: runner request rate against a bare litellm loop, and peak memory."""

from __future__ import annotations

import os
import platform
from datetime import UTC, datetime
from pathlib import Path

import click


def _machine() -> str:
    model = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} cores, {model}, Python {platform.python_version()}"


def _dataset(work: Path, per_horizon: int) -> Path:
    from bpb_core.cli.console import stderr
    from bpb_core.dataset import generate_dataset

    for found in sorted(work.glob("bench-run-data-*")):
        size = found.name.rsplit("-", 1)[-1]
        if size.isdigit() and int(size) >= per_horizon and (found / "dataset.json").exists():
            return found  # a larger dataset serves too: runs take the first N per horizon
    data = work / f"bench-run-data-{per_horizon}"
    stderr().print(f"generating {5 * per_horizon} scenes with images in {data} ...")
    return generate_dataset(data, per_horizon, [1, 2, 3, 4, 5], seed=0)


@click.command("run")
@click.option("--concurrency", type=click.IntRange(min=1), default=64, show_default=True)
@click.option("--latency", type=float, default=1.0, show_default=True, help="Server delay (s).")
@click.option(
    "--throughput-scenes",
    type=click.IntRange(min=1),
    default=43,
    show_default=True,
    help="Scenes per horizon for the rate phases (x5 horizons x3 tasks calls).",
)
@click.option(
    "--memory-scenes",
    type=click.IntRange(min=0),
    default=200,
    show_default=True,
    help="Scenes per horizon for the memory run (200 -> 3,000 calls; 0 skips).",
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
    """Request rate of `bpb run` vs a bare litellm.acompletion loop (server side), peak RSS."""
    from rich.table import Table

    from bpb_core.bench.run import bench_memory, bench_throughput
    from bpb_core.cli.console import stdout

    data = _dataset(work, max(throughput_scenes, memory_scenes))
    bare, ours = bench_throughput(data, concurrency, latency, throughput_scenes, rounds)
    ideal = concurrency / latency
    table = Table(
        "client",
        "requests",
        "seconds",
        "req/s",
        "% of ideal",
        "% of bare",
        "peak RSS MB",
        "exit",
        title=f"bpb bench run: {_machine()}, "
        f"{datetime.now(UTC):%Y-%m-%d}, concurrency {concurrency}, latency {latency:g} s",
    )
    table.add_row("ideal", "", "", f"{ideal:.1f}", "100.0", "", "", "")
    for phase in (bare, ours):
        table.add_row(
            phase.name,
            str(phase.requests),
            f"{phase.seconds:.2f}",
            f"{phase.rate:.1f}",
            f"{100 * phase.rate / ideal:.1f}",
            f"{100 * phase.rate / bare.rate:.1f}",
            f"{phase.peak_rss_mb:.0f}",
            str(phase.exit_code),
        )
    if memory_scenes:
        memory = bench_memory(data, memory_scenes, concurrency)
        table.add_row(
            memory.name,
            str(memory.requests),
            f"{memory.seconds:.1f}",
            f"{memory.rate:.1f}",
            "",
            "",
            f"{memory.peak_rss_mb:.0f}",
            str(memory.exit_code),
        )
    stdout().print(table)
