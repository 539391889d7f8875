"""Scheduling of generation jobs on a process pool, and the progress protocol.

Results come back in job order (``imap``), so the streamed index and checksums are in scene
order however many workers run.
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Callable, Iterable, Iterator
from multiprocessing.pool import Pool
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from bpb_core.dataset.worker import (
    Job,
    SceneResult,
    WorkerSetup,
    calibrate_job,
    init_pool_worker,
    init_worker,
    remove_scene,
    run_job,
    started_pool,
)
from bpb_core.dataset.writer import DatasetWriter, plugin_label
from bpb_core.errors import BadInput
from bpb_core.plugin_calls import simulator_named
from bpb_core.simulator_spec import parse_spec

if TYPE_CHECKING:
    from bpb_core.registry import Registry

MAX_DRAWS_FACTOR = 50  # --stable-only gives up after this many draws per wanted scene
WORKERS_PER_CORE = 4  # beyond, processes only queue for the cores, each with its own memory
# 50 times the largest size in the docs (10,000 per horizon); 500,000 scenes over five horizons
# are about 50 GB with images and hours of work, so more is a typo, not a dataset
MAX_PER_HORIZON = 100_000


def check_per_horizon(count: int, option: str = "--per-horizon", least: int = 1) -> None:
    """Refuse a count of scenes per horizon below ``least`` or above :data:`MAX_PER_HORIZON`.

    Raises:
        BadInput: ``"--per-horizon: must be at least 1, got 0"`` or
            ``"--per-horizon: at most 100,000 scenes per horizon, got 2,000,000,000"``.
    """
    if count < least:
        raise BadInput(f"{option}: must be at least {least}, got {count}")
    if count > MAX_PER_HORIZON:
        raise BadInput(f"{option}: at most {MAX_PER_HORIZON:,} scenes per horizon, got {count:,}")


def check_workers(workers: int | None, least: int = 1) -> None:
    """Refuse a ``--workers`` count below ``least`` or above :data:`WORKERS_PER_CORE` per core
    (``None``: the command's default).

    Raises:
        BadInput: ``"--workers: must be at least 1, got 0"`` or ``"--workers: at most 8 ..."``.
    """
    if workers is None:
        return
    if workers < least:
        raise BadInput(f"--workers: must be at least {least}, got {workers}")
    most = WORKERS_PER_CORE * (os.cpu_count() or 1)
    if workers > most:
        raise BadInput(
            f"--workers: at most {most} ({WORKERS_PER_CORE} per core; more only wait for a "
            f"core), got {workers}"
        )


class GenerateProgress(Protocol):
    """Receives generation progress (the CLI draws a bar; the library never prints)."""

    def phase(self, name: str, total: int) -> None:
        """A new phase (``calibrate``, ``scenes``, ``stats``) with ``total`` steps begins."""
        ...

    def advance(self, count: int = 1) -> None:
        """``count`` steps of the current phase are done."""
        ...


class NoProgress:
    """Ignores progress."""

    def phase(self, name: str, total: int) -> None:
        return None

    def advance(self, count: int = 1) -> None:
        return None


def worker_setup(
    registry: Registry, family: str, root: Path, seed: int, config: Any, images: bool
) -> WorkerSetup:
    """Resolve the family and the simulator its config names (with its options) into a
    picklable setup."""
    family_entry = registry.get("scene_family", family)
    named = simulator_named(registry.scene_family(family), family_entry.origin, config)
    spec = parse_spec(named, "config: simulator")
    simulator = spec.name
    simulator_entry = registry.get("simulator", simulator)
    plugins = (
        ("scene_family", plugin_label(family_entry)),
        ("simulator", plugin_label(simulator_entry)),
    )
    return WorkerSetup(
        root=root,
        seed=seed,
        config=config,
        family_cls=registry.load("scene_family", family),
        simulator_cls=registry.load("simulator", simulator),
        images=images,
        origin=family_entry.origin,
        plugins=plugins,
        options=tuple(spec.options.items()),
        simulator=simulator,
        simulator_origin=simulator_entry.origin,
        simulator_spec=spec.spec,
    )


class InProcess:
    """The part of :class:`multiprocessing.pool.Pool` used here, run in this process."""

    def __init__(self, setup: WorkerSetup) -> None:
        init_worker(setup)

    def imap(
        self, func: Callable[[Any], Any], items: Iterable[Any], chunksize: int = 1
    ) -> Iterator[Any]:
        return map(func, items)

    def __enter__(self) -> InProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        return None


def pooled(n_workers: int) -> bool:
    """Whether ``n_workers`` run in a pool of worker processes, whose first job this process
    does itself before the pool starts: forked workers (the default on Linux up to Python
    3.13) inherit what it loaded; spawned ones (macOS, and Linux's forkserver from 3.14) load
    from the disk caches it filled, such as a plugin's compiled code, instead of each building
    it at once (and giving its notice once each)."""
    return n_workers > 1


def make_pool(n_workers: int, setup: WorkerSetup) -> Pool | InProcess:
    """A pool of ``n_workers`` initialised with ``setup`` (in-process when 1)."""
    if n_workers == 1:
        return InProcess(setup)
    return started_pool(lambda: Pool(n_workers, init_pool_worker, (setup,)))


def run_calibration(
    n_workers: int, setup: WorkerSetup, hs: list[float], progress: GenerateProgress
) -> dict[float, Any]:
    """Calibrate each horizon on ``n_workers`` processes, one horizon per job; results keyed by
    horizon. With a pool, the first horizon is calibrated in this process before the pool
    starts (:func:`pooled`), as :func:`run_scenes` makes its first scene."""
    progress.phase("calibrate", len(hs))
    found: dict[float, Any] = {}
    ahead = hs[:1] if pooled(n_workers) else []
    if ahead:
        found.update(InProcess(setup).imap(calibrate_job, ahead))
        progress.advance()
    with make_pool(n_workers, setup) as pool:
        for horizon, result in pool.imap(calibrate_job, hs[len(ahead) :]):
            found[horizon] = result
            progress.advance()
    return found


def run_scenes(
    n_workers: int,
    setup: WorkerSetup,
    writer: DatasetWriter,
    hs: list[float],
    per_horizon: int,
    stable_only: bool,
    progress: GenerateProgress,
) -> None:
    """Produce every scene on ``n_workers`` processes and stream the results to ``writer`` in
    scene order.

    With a pool, the first scene is made in this process before the pool starts (:func:`pooled`),
    so that forked workers inherit what making it loaded (imports, compiled code, image caches)
    instead of each loading it again (docs/benchmarks.md: about 6% less CPU for the paper-size
    dataset on 2 workers, the same wall time), and no worker builds what it built (a plugin's
    compiled code on first use: once, and its notice given once).
    """
    progress.phase("scenes", per_horizon * len(hs))
    if stable_only:
        first = None
        if pooled(n_workers):
            first = next(_results(InProcess(setup), [Job(hs[0], 0, keep_unstable=False)]))
        with make_pool(n_workers, setup) as pool:
            for h in hs:
                _run_stable(pool, setup, writer, h, per_horizon, progress, first)
                first = None
        return
    jobs = (Job(h, i) for h in hs for i in range(per_horizon))
    if pooled(n_workers):
        _stream(InProcess(setup), itertools.islice(jobs, 1), writer, progress)
    with make_pool(n_workers, setup) as pool:
        _stream(pool, jobs, writer, progress)


def _stream(
    pool: Pool | InProcess, jobs: Iterable[Job], writer: DatasetWriter, progress: GenerateProgress
) -> None:
    """Run ``jobs`` on ``pool`` and hand each result to ``writer`` in job order."""
    for result in _results(pool, jobs):
        writer.add(result)
        progress.advance()


def _results(pool: Pool | InProcess, jobs: Iterable[Job]) -> Iterator[SceneResult]:
    """The results of ``jobs`` run on ``pool``, in job order; a scene's error is raised after
    the results of the scenes before it."""
    return pool.imap(run_job, jobs)


def _run_stable(
    pool: Pool | InProcess,
    setup: WorkerSetup,
    writer: DatasetWriter,
    h: float,
    per_horizon: int,
    progress: GenerateProgress,
    first: SceneResult | None = None,
) -> None:
    """Keep the first ``per_horizon`` stable indices of horizon ``h`` (drawn in batches);
    ``first``: index 0's result, made before the pool started."""
    kept, start = 0, 0
    while kept < per_horizon:
        if start > MAX_DRAWS_FACTOR * per_horizon + 100:
            raise BadInput(
                f"--stable-only: horizon {h:g} s: only {kept} of {start} scenes drawn were stable "
                f"(generation gives up after {MAX_DRAWS_FACTOR} draws per scene wanted, plus 100); "
                "ask for fewer scenes or loosen the config's stability settings"
            )
        size = max(8, 2 * (per_horizon - kept))
        batch = [Job(h, i, keep_unstable=False) for i in range(start, start + size)]
        start += size
        ahead, first = [] if first is None else [first], None
        made = _results(pool, batch[len(ahead) :])
        for result in itertools.chain(ahead, made):
            if kept >= per_horizon:
                if result.written:
                    remove_scene(setup.root, h, result.row.index)
            elif result.row.stable is False:
                writer.drop(h)
            else:
                writer.add(result)
                kept += 1
                progress.advance()
