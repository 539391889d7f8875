"""``bpb bench startup``."""

from __future__ import annotations

import click

from bpb_core.cli.console import stdout


@click.command("startup")
@click.option("--runs", default=20, show_default=True, help="Interleaved runs per command.")
def startup(runs: int) -> None:
    """Time `bpb --help` against a bare `python -c pass` (target: at most +300 ms)."""
    from rich.table import Table

    from bpb_core.bench.startup import measure_startup

    result = measure_startup(runs)
    table = Table("command", "median ms", title=f"bpb start-up ({runs} interleaved runs)")
    table.add_row("python -c pass", f"{result.bare_ms:.1f}")
    table.add_row("bpb --help", f"{result.help_ms:.1f}")
    table.add_row("bpb --version", f"{result.version_ms:.1f}")
    table.add_row("overhead of bpb --help", f"{result.overhead_ms:.1f}")
    stdout().print(table)
