"""``bpb bench startup``: start-up time of the ``bpb`` command beside a bare interpreter."""

from __future__ import annotations

import click


@click.command("startup")
@click.option(
    "--runs", type=click.IntRange(min=1), default=20, show_default=True, help="Interleaved runs."
)
def bench_startup(runs: int) -> None:
    """Time `bpb --help` against a bare `python -c pass` (target: at most +300 ms)."""
    from rich.table import Table

    from bpb_core.bench.startup import measure_startup
    from bpb_core.cli.console import stdout

    result = measure_startup(runs)
    table = Table("command", "median ms", title=f"bpb start-up ({runs} interleaved runs)")
    table.add_row("python -c pass", f"{result.bare_ms:.1f}")
    table.add_row("bpb --help", f"{result.help_ms:.1f}")
    table.add_row("bpb --version", f"{result.version_ms:.1f}")
    table.add_row("overhead of bpb --help", f"{result.overhead_ms:.1f}")
    stdout().print(table)
