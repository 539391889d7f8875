"""``bpb run --dry-run``: the table of what a run would send (from bpb_core.runner.dry_run)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from bpb_core.cli.run_file import Prepared
    from bpb_core.dataset.reader import DataFolder
    from bpb_core.registry import Registry
    from bpb_core.runner.options import RunOptions


def show_dry_run(
    data: DataFolder, out: Path, ready: list[Prepared], options: RunOptions, registry: Registry
) -> None:
    """Print, per adapter and task, the calls a run would send, those already done, and the
    estimated input tokens and USD (nothing is sent)."""
    from rich.markup import escape
    from rich.table import Table

    from bpb_core.cli.console import stdout
    from bpb_core.runner import slug
    from bpb_core.runner.dry_run import dry_run

    table = Table(
        "adapter",
        "task",
        "calls",
        "already done",
        "est. input tokens",
        "est. input USD",
        title="bpb run --dry-run (nothing sent; output tokens not included)",
    )
    for item in ready:
        plan = dry_run(data, out / slug(item.name), options, registry, item.adapter, item.origin)
        for task in options.tasks:
            cost = plan.input_cost.get(task, 0.0)
            table.add_row(
                escape(item.name),
                task,
                str(plan.calls.get(task, 0)),
                str(plan.done.get(task, 0)),
                f"{plan.input_tokens.get(task, 0):,}",
                "no price" if cost is None else f"${cost:.4f}",
            )
    stdout().print(table)
