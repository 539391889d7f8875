"""Generate a dataset (:func:`generate_dataset`) and read one (:func:`load_dataset`).

Generation runs one job per scene on a process pool; each worker writes its scene folder and
returns a small row, which the parent streams into ``index.csv`` and ``checksums.sha256`` in
scene order. Every scene's randomness comes from (seed, horizon, index), so the same arguments
give byte-identical datasets whatever the number of workers.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.dataset.jobs import (
    GenerateProgress,
    NoProgress,
    make_pool,
    run_calibration,
    run_scenes,
    worker_setup,
)
from bpb_core.dataset.manifest import DatasetManifest
from bpb_core.dataset.reader import Dataset, load_dataset
from bpb_core.dataset.worker import WorkerSetup
from bpb_core.dataset.writer import DatasetWriter, versions
from bpb_core.errors import BadInput
from bpb_core.layout import MANIFEST

if TYPE_CHECKING:
    from bpb_tasks.billiards.calibrate import Calibration
    from bpb_tasks.billiards.config import DatasetConfig

__all__ = ["Dataset", "GenerateProgress", "NoProgress", "generate_dataset", "load_dataset"]


def generate_dataset(
    out: str | Path,
    per_horizon: int,
    horizons: Sequence[float],
    seed: int,
    config: DatasetConfig | Mapping[str, Any] | str | Path | None = None,
    progress: GenerateProgress | None = None,
    *,
    stable_only: bool = False,
    workers: int | None = None,
    images: bool = True,
    calibrate: bool = False,
    overwrite: bool = False,
) -> Path:
    """Generate a dataset folder (SPEC section 4 layout) and return its path.

    The folder is built beside ``out`` under a hidden ``.NAME.partial`` name and renamed at the
    end, so an interrupted generation never leaves a folder that looks complete.

    Args:
        out: Folder to create; it must not exist or be empty (or be a dataset, with
            ``overwrite``).
        per_horizon: Scenes per horizon.
        horizons: Horizons in seconds.
        seed: Dataset seed; scene ``i`` at horizon ``t`` is drawn from (seed, t, i).
        config: A :class:`~bpb_tasks.billiards.config.DatasetConfig`, a mapping of its fields or
            a JSON/TOML file; ``None`` uses the defaults.
        progress: Receives progress; nothing is printed.
        stable_only: Keep only scenes whose stability annotation is stable: unstable draws are
            skipped and further indices drawn until ``per_horizon`` are kept (scene indices then
            have gaps; the dropped count per horizon is in the manifest).
        workers: Processes (default: all cores); 1 runs in this process.
        images: Render ``init.png``, ``final.png`` and ``trajectory.png``.
        calibrate: Recompute the per-horizon cue-speed ranges first (recorded in the manifest).
        overwrite: Replace an existing dataset folder at ``out``.

    Raises:
        BadInput: Bad arguments or config (the message names the file or field).
    """
    cfg = resolve_config(config)
    hs = _check_args(per_horizon, horizons)
    if not calibrate:
        for h in hs:
            cfg.speed_range(h)  # fail before touching the disk
    progress = progress or NoProgress()
    target = Path(out)
    partial = _prepare(target, overwrite)
    n_workers = max(1, workers or os.cpu_count() or 1)
    setup = worker_setup(partial, seed, cfg, images)
    calibration = None
    if calibrate:
        with make_pool(n_workers, setup) as pool:
            calibration = run_calibration(pool, hs, progress)
        ranges = {key: c.range for key, c in calibration.items()}
        setup = replace(setup, config=cfg.with_ranges(ranges))
    writer = DatasetWriter(partial, hs)
    try:
        with make_pool(n_workers, setup) as pool:
            run_scenes(pool, setup, writer, hs, per_horizon, stable_only, progress)
        _write_stats(setup, writer, progress)
    finally:
        writer.close()
    writer.write_manifest(_manifest(setup, writer, hs, per_horizon, stable_only, calibration))
    if target.exists():
        shutil.rmtree(target)
    partial.rename(target)
    return target


def resolve_config(config: DatasetConfig | Mapping[str, Any] | str | Path | None) -> DatasetConfig:
    """A :class:`DatasetConfig` from any accepted form (see :func:`generate_dataset`)."""
    from bpb_tasks.billiards.config import DatasetConfig, config_from_mapping, load_config

    if isinstance(config, DatasetConfig):
        return config
    if config is None or isinstance(config, str | Path):
        return load_config(config)
    return config_from_mapping(config)


def _check_args(per_horizon: int, horizons: Sequence[float]) -> list[float]:
    if per_horizon < 1:
        raise BadInput(f"per_horizon: must be at least 1, got {per_horizon}")
    hs = [float(h) for h in horizons]
    if not hs:
        raise BadInput("horizons: give at least one horizon")
    bad = [h for h in hs if not h > 0]
    if bad:
        raise BadInput(f"horizons: must be positive seconds, got {bad[0]:g}")
    if len(set(hs)) != len(hs):
        raise BadInput("horizons: a horizon is listed twice")
    return hs


def _prepare(target: Path, overwrite: bool) -> Path:
    if target.exists() and (not target.is_dir() or any(target.iterdir())):
        is_dataset = (target / MANIFEST).is_file()
        if not (overwrite and is_dataset):
            hint = "pass --overwrite" if is_dataset else "choose a new or empty folder"
            raise BadInput(f"{target}: --out: exists and is not an empty folder; {hint}")
    partial = target.parent / f".{target.name}.partial"
    if partial.exists():
        shutil.rmtree(partial)  # left over from an interrupted generation
    partial.mkdir(parents=True)
    return partial


def _write_stats(setup: WorkerSetup, writer: DatasetWriter, progress: GenerateProgress) -> None:
    from bpb_tasks.billiards.stats import write_stats

    progress.phase("stats", 1)
    cfg = setup.config
    ranges = {h: (cfg.speed_range(h).low, cfg.speed_range(h).high) for h in writer.tallies}
    for rel in write_stats(setup.root, writer.tallies, ranges):
        writer.add_file(rel)
    progress.advance()


def _manifest(
    setup: WorkerSetup,
    writer: DatasetWriter,
    hs: list[float],
    per_horizon: int,
    stable_only: bool,
    calibration: dict[str, Calibration] | None,
) -> DatasetManifest:
    cfg = setup.config
    ranges = {h: (cfg.speed_range(h).low, cfg.speed_range(h).high) for h in hs}
    summary = writer.summary(ranges)
    return DatasetManifest(
        seed=setup.seed,
        per_horizon=per_horizon,
        horizons=hs,
        stable_only=stable_only,
        images=setup.images,
        scenes=sum(s.scenes for s in summary.values()),
        summary=summary,
        config=cfg.model_dump(mode="json"),
        physics={
            **cfg.physics.model_dump(mode="json"),
            "table": cfg.table.model_dump(mode="json"),
            "pockets": cfg.pockets.model_dump(mode="json"),
        },
        calibration=None if calibration is None else _calibration_record(calibration),
        plugins=dict(setup.plugins),
        versions=versions(),
    )


def _calibration_record(calibration: dict[str, Calibration]) -> dict[str, Any]:
    return {
        key: {"low": c.range.low, "high": c.range.high, "rate": c.rate, "samples": c.samples}
        for key, c in calibration.items()
    }
