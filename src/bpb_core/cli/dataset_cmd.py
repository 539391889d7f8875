"""``bpb generate`` (a thin wrapper over :func:`bpb_core.dataset.generate_dataset`) and ``bpb
export`` (publish a dataset folder in another tool's format: a Hugging Face dataset)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import click

from bpb_core.cli import console
from bpb_core.cli.console import PATH
from bpb_core.errors import BadInput

if TYPE_CHECKING:
    from rich.progress import Progress, TaskID

    from bpb_core.dataset.generate import GenerateProgress
    from bpb_core.dataset.manifest import DatasetManifest


PHASES = {"calibrate": "calibrating", "scenes": "scenes", "stats": "stats figures"}


def parse_horizons(text: str) -> list[float]:
    """``"1,2,3"`` to ``[1.0, 2.0, 3.0]``; raises :class:`BadInput` naming ``--horizons``."""
    values = []
    for part in text.split(","):
        try:
            value = float(part.strip())
        except ValueError:
            raise BadInput(f"--horizons: {part.strip()!r} is not a number of seconds") from None
        if not value > 0 or value != value or value == float("inf"):
            raise BadInput(f"--horizons: {part.strip()!r} must be a positive number of seconds")
        values.append(value)
    return values


class RichProgress:
    """Draws :class:`~bpb_core.dataset.generate.GenerateProgress` events on rich progress bars."""

    def __init__(self, bar: Progress) -> None:
        self._bar = bar
        self._task: TaskID | None = None

    def phase(self, name: str, total: int) -> None:
        self._task = self._bar.add_task(PHASES.get(name, name), total=total)

    def advance(self, count: int = 1) -> None:
        if self._task is not None:
            self._bar.advance(self._task, count)


@contextmanager
def _progress() -> Iterator[GenerateProgress]:
    """The bars in a terminal; in a log or a pipe, where rich would draw nothing, no bar at
    all: it costs its import and time per scene even when drawing nothing."""
    from bpb_core.dataset.generate import NoProgress

    if not console.stderr().is_terminal:
        yield NoProgress()
        return
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    columns = (BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(TextColumn("{task.description:<20}"), *columns, console=console.stderr()) as bar:
        yield RichProgress(bar)


def show_summary(root: Path, manifest: DatasetManifest) -> None:
    """Print per-horizon counts: scenes, the scene family's own figures (such as a realised
    collision rate), unstable scenes."""
    from rich.table import Table

    from bpb_core.layout import horizon_label

    summaries = [manifest.summary[horizon_label(h)] for h in manifest.horizons]
    extra = list(dict.fromkeys(k for s in summaries for k in (s.model_extra or {})))
    family = manifest.family or "unknown family"
    table = Table(title=f"{root}: {manifest.scenes} {family} scenes, seed {manifest.seed}")
    for column in ("horizon", "scenes", *(k.replace("_", " ") for k in extra), "unstable"):
        table.add_column(column, justify="right")
    for horizon, s in zip(manifest.horizons, summaries, strict=True):
        unstable = str(s.unstable) if not manifest.stable_only else f"{s.dropped_unstable} dropped"
        cells = [_figure(k, (s.model_extra or {}).get(k)) for k in extra]
        table.add_row(horizon_label(horizon), str(s.scenes), *cells, unstable)
    console.stdout().print(table)


def _figure(name: str, value: object) -> str:
    """A family's summary figure as text: rates as percentages, ranges as ``low to high``."""
    if value is None:
        return "–"
    if isinstance(value, float) and name.endswith("rate"):
        return f"{value:.1%}"
    if isinstance(value, list | tuple) and len(value) == 2:
        return f"{value[0]:g} to {value[1]:g}"
    return f"{value:g}" if isinstance(value, float) else str(value)


@click.command("generate")
@click.option("--out", required=True, type=PATH, help="Folder.")
@click.option(
    "--family",
    help="Scene family plugin [default: the default one; see bpb list scene-families].",
)
@click.option(
    "--per-horizon", default=200, show_default=True, help="Scenes per horizon (at most 100,000)."
)
@click.option("--horizons", default="1,2,3,4,5", show_default=True, help="Seconds, comma list.")
@click.option("--seed", default=0, show_default=True, help="Dataset seed.")
@click.option("--config", "config_path", type=PATH, help="JSON/TOML config.")
@click.option("--stable-only", is_flag=True, help="Draw until N stable scenes per horizon.")
@click.option(
    "--workers", type=int, default=None, help="Processes, at most 4 per core [default: all cores]."
)
@click.option("--no-images", is_flag=True, help="Skip the PNGs (JSON and stats only).")
@click.option("--calibrate", is_flag=True, help="Recalibrate the family's sampling first.")
@click.option("--overwrite", is_flag=True, help="Replace an existing dataset at --out.")
def generate(
    out: Path,
    family: str | None,
    per_horizon: int,
    horizons: str,
    seed: int,
    config_path: Path | None,
    stable_only: bool,
    workers: int | None,
    no_images: bool,
    calibrate: bool,
    overwrite: bool,
) -> None:
    """Generate a dataset: scenes, ground truth, images, index, stats and manifest."""
    from bpb_core.dataset.generate import check_per_horizon, check_workers, generate_dataset
    from bpb_core.dataset.reader import read_manifest

    check_per_horizon(per_horizon)
    check_workers(workers)
    hs = parse_horizons(horizons)
    registry = console.load_registry()
    if family is not None:
        registry.get("scene_family", family)  # unknown names fail before anything starts
    with _progress() as progress:
        root = generate_dataset(
            out,
            per_horizon,
            hs,
            seed,
            config=config_path,
            progress=progress,
            stable_only=stable_only,
            workers=workers,
            images=not no_images,
            calibrate=calibrate,
            overwrite=overwrite,
            family=family,
            registry=registry,
        )
    show_summary(root, read_manifest(root))


@click.command("export")
@click.argument("data", type=PATH)
@click.option(
    "--format",
    "fmt",
    type=click.Choice(["hf"]),
    default="hf",
    show_default=True,
    help="hf: Parquet shards with an Image feature, split by horizon, and a dataset card.",
)
@click.option("--out", required=True, type=PATH, help="Export folder.")
@click.option("--tasks", help="Comma-separated tasks [default: the family's].")
@click.option(
    "--shard-rows", default=1000, show_default=True, help="Rows per Parquet file at most."
)
def export(data: Path, fmt: str, out: Path, tasks: str | None, shard_rows: int) -> None:
    """Export the dataset folder DATA (one row per scene and task).

    Load the result with `datasets.load_dataset("parquet", data_dir=OUT)` or run on it with
    `bpb run --data OUT`.
    """
    from bpb_core.library.hf_export import export_hf

    if shard_rows < 1:
        raise BadInput("--shard-rows: must be at least 1")
    names = [name.strip() for name in tasks.split(",") if name.strip()] if tasks else None
    done = export_hf(data, out, tasks=names, shard_rows=shard_rows)
    rows = ", ".join(f"{split}: {count}" for split, count in done.splits.items())
    console.stdout().print(
        f"exported {sum(done.splits.values())} rows ({rows}) of {', '.join(done.tasks)} "
        f"in {len(done.files)} Parquet file(s) to {done.out}",
        highlight=False,
    )
