"""``bpb bench ...``: benchmarks that write the figures of docs/benchmarks.md.

Each benchmark lives in its own module and is imported only when run.
"""

from __future__ import annotations

import importlib

import click

# name -> (module, attribute, one-line help)
BENCH_COMMANDS: dict[str, tuple[str, str, str]] = {
    "generate": (
        "bpb_core.cli.bench_generate_cmd",
        "bench_generate",
        "Dataset generation time beside Pillow-only PNG encoding.",
    ),
    "startup": ("bpb_core.cli.bench_startup_cmd", "startup", "Start-up time of the bpb command."),
    "sim": ("bpb_core.cli.bench_sim_cmd", "sim", "Simulators: speed against error."),
    "run": ("bpb_core.cli.bench_run_cmd", "bench_run", "Runner request rate vs bare litellm; RSS."),
    "score": ("bpb_core.cli.bench_score_cmd", "bench_score_cmd", "Scoring speed (1M rows)."),
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
        if rows:
            with formatter.section("Benchmarks"):
                formatter.write_dl(rows)


@click.group("bench", cls=_LazyBench)
def bench() -> None:
    """Benchmarks: run side by side in one process, print a table, write figures."""
