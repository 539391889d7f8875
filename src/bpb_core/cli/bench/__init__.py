"""``bpb bench ...``: benchmarks that write the figures of docs/benchmarks.md.

Each benchmark's command is a module of this package (its library is the module of the same
name in :mod:`bpb_core.bench`); it is imported only when run, so ``bpb bench --help`` lists
them from the table below without importing any.
"""

from __future__ import annotations

import importlib

import click

# name -> (module, attribute, one-line help)
BENCH_COMMANDS: dict[str, tuple[str, str, str]] = {
    "extract": (
        "bpb_core.cli.bench.extract",
        "bench_extract",
        "Answer extraction on adversarial replies up to 1 MB (linear time).",
    ),
    "generate": (
        "bpb_core.cli.bench.generate",
        "bench_generate",
        "Dataset generation time beside Pillow-only image encoding.",
    ),
    "run": ("bpb_core.cli.bench.run", "bench_run", "Runner request rate vs bare litellm; RSS."),
    "score": (
        "bpb_core.cli.bench.score",
        "bench_score",
        "Scoring speed of every scorer (1M rows).",
    ),
    "sim": ("bpb_core.cli.bench.sim", "bench_sim", "Simulators: speed against error."),
    "startup": ("bpb_core.cli.bench.startup", "bench_startup", "Start-up time of the bpb command."),
}


class _LazyBench(click.Group):
    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(BENCH_COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        entry = BENCH_COMMANDS.get(cmd_name)
        if entry is None:
            return None
        command = getattr(importlib.import_module(entry[0]), entry[1])
        assert isinstance(command, click.Command)
        return command

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        rows = [(n, BENCH_COMMANDS[n][2]) for n in self.list_commands(ctx)]
        with formatter.section("Benchmarks"):
            formatter.write_dl(rows)


@click.group("bench", cls=_LazyBench)
def bench() -> None:
    """Benchmarks: run side by side in one process, print a table, write figures."""
