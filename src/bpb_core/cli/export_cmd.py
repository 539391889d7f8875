"""``bpb export``: publish a dataset folder in another tool's format (a Hugging Face dataset)."""

from __future__ import annotations

from pathlib import Path

import click


@click.command("export")
@click.argument("data", type=click.Path(path_type=Path))
@click.option(
    "--format",
    "fmt",
    type=click.Choice(["hf"]),
    default="hf",
    show_default=True,
    help="hf: Parquet shards with an Image feature, split by horizon, and a dataset card.",
)
@click.option("--out", required=True, type=click.Path(path_type=Path), help="Export folder.")
@click.option("--tasks", default=None, help="Comma-separated tasks [default: the family's].")
@click.option(
    "--shard-rows", default=1000, show_default=True, help="Rows per Parquet file at most."
)
def export(data: Path, fmt: str, out: Path, tasks: str | None, shard_rows: int) -> None:
    """Export the dataset folder DATA (one row per scene and task).

    Load the result with `datasets.load_dataset("parquet", data_dir=OUT)` or run on it with
    `bpb run --data OUT`.
    """
    from bpb_core.cli.console import stdout
    from bpb_core.errors import BadInput
    from bpb_core.library.hf_export import export_hf

    if shard_rows < 1:
        raise BadInput("--shard-rows: must be at least 1")
    names = [name.strip() for name in tasks.split(",") if name.strip()] if tasks else None
    done = export_hf(data, out, tasks=names, shard_rows=shard_rows)
    rows = ", ".join(f"{split}: {count}" for split, count in done.splits.items())
    stdout().print(
        f"exported {sum(done.splits.values())} rows ({rows}) of {', '.join(done.tasks)} "
        f"in {len(done.files)} Parquet file(s) to {done.out}",
        highlight=False,
    )
