"""``bpb bench extract``: answer extraction time on adversarial replies of growing size."""

from __future__ import annotations

import click


@click.command("extract")
@click.option(
    "--repeats", default=5, show_default=True, help="Timed repeats, at most 100 (best kept)."
)
def bench_extract(repeats: int) -> None:
    """Time the reply extractor at 250 kB, 500 kB and 1 MB (target: under 50 ms at 1 MB, time
    growing linearly); exit 1 when a 1 MB reply is slower."""
    from rich.table import Table

    from bpb_core.bench import MAX_REPEATS
    from bpb_core.bench.extract import TARGET_MS, bench_extract as run
    from bpb_core.cli.console import stdout
    from bpb_core.errors import BadInput

    if repeats < 1:
        raise BadInput("--repeats: must be at least 1")
    if repeats > MAX_REPEATS:
        raise BadInput(f"--repeats: at most {MAX_REPEATS}, got {repeats:,}")
    sizes = (250_000, 500_000, 1_000_000)
    timings = run(sizes, repeats)
    title = f"Answer extraction (target: under {TARGET_MS:g} ms on any 1 MB reply)"
    columns = [f"{s // 1000:,} kB ms" for s in sizes]
    table = Table("reply", *columns, "1 MB / 250 kB", title=title)
    slow = False
    for family in dict.fromkeys(t.family for t in timings):
        row = [t.best_ms for t in timings if t.family == family]
        slow = slow or row[-1] > TARGET_MS
        ratio = row[-1] / row[0] if row[0] > 0.05 else float("nan")
        table.add_row(family, *(f"{ms:.2f}" for ms in row), f"{ratio:.1f}")
    stdout().print(table)
    if slow:
        raise click.exceptions.Exit(1)
