"""``bpb bench generate``: generation seconds beside PNG encoding alone; optional memory."""

from __future__ import annotations

import click


@click.command("generate")
@click.option(
    "--per-horizon",
    default=200,
    show_default=True,
    help="Scenes per horizon (x5; at most 100,000).",
)
@click.option(
    "--workers", type=int, default=None, help="Processes, at most 4 per core [default: all cores]."
)
@click.option(
    "--memory",
    "memory",
    default="",
    help="Also measure peak RSS at these per-horizon sizes, e.g. 200,2000 (each at most 100,000).",
)
def bench_generate(per_horizon: int, workers: int | None, memory: str) -> None:
    """Seconds for a dataset (1,000 scenes by default) beside PNG encoding alone."""
    from rich.table import Table

    from bpb_core.bench.generate import measure_generate, measure_memory
    from bpb_core.cli.console import stdout
    from bpb_core.dataset.jobs import check_per_horizon, check_workers
    from bpb_core.errors import BadInput

    try:
        sizes = [int(x) for x in memory.split(",") if x.strip()]
    except ValueError:
        raise BadInput(f"--memory: expected comma-separated numbers, got {memory!r}") from None
    check_per_horizon(per_horizon)
    for scenes in sizes:
        check_per_horizon(scenes, "--memory")
    check_workers(workers)
    t = measure_generate(per_horizon, workers=workers)
    size = f" of {t.size[0]}x{t.size[1]} px" if t.size else ""
    plural = "s" if t.workers != 1 else ""
    title = f"{t.scenes} scenes, {t.images} images{size}, {t.workers} worker{plural}"
    table = Table("variant", "seconds", "per scene ms", title=title)
    rows = [
        (f"bpb generate (scenes, truth, {t.images_per_scene:g} images per scene)", t.generate_s),
        ("bpb generate --no-images", t.no_images_s),
        (f"Pillow alone: {t.images} RGB PNGs, default settings", t.pillow_default_s),
        (f"Pillow alone: {t.images} palette PNGs, zlib level 1", t.pillow_palette_s),
    ]
    for name, seconds in rows:
        if seconds is not None:
            table.add_row(name, f"{seconds:.2f}", f"{1000 * seconds / t.scenes:.2f}")
    stdout().print(table)
    if sizes:
        mem = Table("scenes", "seconds", "parent peak MiB", "largest worker MiB", title="Memory")
        for scenes in sizes:
            m = measure_memory(scenes, workers)
            worker = "–" if m.worker_mib is None else f"{m.worker_mib:.1f}"  # none with 1
            mem.add_row(str(m.scenes), f"{m.seconds:.1f}", f"{m.parent_mib:.1f}", worker)
        stdout().print(mem)
