"""Generate a dataset (:func:`generate_dataset`) with a scene family plugin: the generation
jobs, one scene from seed to files, and their scheduling on a process pool.

A worker (a pool process, or this one for ``workers=1``) asks the family for a scene, writes
its folder and returns a small :class:`SceneResult`, so nothing accumulates in memory however
large the dataset is. Results come back in job order (``imap``), and the parent streams them
into ``index.csv`` and ``checksums.sha256`` in scene order however many workers run. Every
scene's randomness comes from (seed, horizon, index), so the same arguments give
byte-identical datasets whatever the number of workers.
"""

from __future__ import annotations

import itertools
import math
import os
import shutil
import signal
import traceback
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, replace
from multiprocessing.pool import Pool
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from bpb_core.capabilities import Calibrating, DrawingStats, ExpectsWork, HorizonTally, Tallying
from bpb_core.dataset.manifest import (
    DatasetManifest,
    DatasetWriter,
    IndexRow,
    sha256_bytes,
    versions,
)
from bpb_core.errors import (
    BadInput,
    BpbError,
    Interrupted,
    PluginBug,
    UnknownName,
    WriteRefused,
    blamed,
    writing,
)
from bpb_core.interfaces import GeneratedScene, SceneFamily, Simulator
from bpb_core.layout import MANIFEST, check_writable_folder, partial_folder, scene_dir, scene_id
from bpb_core.plugin_calls import (
    family_label,
    family_model,
    json_values,
    loaded_config,
    returned,
    simulator_named,
)
from bpb_core.simulator_spec import SimulatorSpec, parse_spec

if TYPE_CHECKING:
    from bpb_core.registry import Registry
    from bpb_core.simulator_spec import SimulatorSpec


RUN = 8  # scenes per pool task: a message each way per run of scenes, not per scene
MAX_DRAWS_FACTOR = 50  # --stable-only gives up after this many draws per wanted scene
WORKERS_PER_CORE = 4  # beyond, processes only queue for the cores, each with its own memory
# 50 times the largest size in the docs (10,000 per horizon); 500,000 scenes over five horizons
# are about 50 GB with images and hours of work, so more is a typo, not a dataset
MAX_PER_HORIZON = 100_000


def check_per_horizon(count: int, option: str = "--per-horizon") -> None:
    """Refuse a count of scenes per horizon below 1 or above :data:`MAX_PER_HORIZON`.

    Raises:
        BadInput: ``"--per-horizon: must be at least 1, got 0"`` or
            ``"--per-horizon: at most 100,000 scenes per horizon, got 2,000,000,000"``.
    """
    if count < 1:
        raise BadInput(f"{option}: must be at least 1, got {count}")
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
    registry: Registry,
    family: str,
    root: Path,
    seed: int,
    config: Any,
    images: bool,
    spec: SimulatorSpec | None = None,
) -> WorkerSetup:
    """Resolve the family and the simulator its config names (``spec``, with its options, when
    the caller parsed it already) into a picklable setup."""
    family_entry = registry.get("scene_family", family)
    if spec is None:
        named = simulator_named(registry.scene_family(family), family_entry.origin, config)
        spec = parse_spec(named, "config: simulator")
    simulator_entry = registry.get("simulator", spec.name)
    plugins = tuple(  # name (distribution version) of each
        (e.info.kind, f"{e.info.name} ({e.distribution} {e.version})")
        for e in (family_entry, simulator_entry)
    )
    return WorkerSetup(
        root=root,
        seed=seed,
        config=config,
        family_cls=registry.load("scene_family", family),
        simulator_cls=registry.load("simulator", spec.name),
        images=images,
        origin=family_entry.origin,
        spec=spec,
        simulator_origin=simulator_entry.origin,
        plugins=plugins,
    )


class InProcess:
    """The part of :class:`multiprocessing.pool.Pool` used here, run in this process."""

    def __init__(self, setup: WorkerSetup) -> None:
        init_worker(setup)

    def imap(self, func: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[Any]:
        return map(func, items)


def pooled(n_workers: int) -> bool:
    """Whether ``n_workers`` run in a pool of worker processes, whose first job this process
    does itself before the pool starts: forked workers (the default on Linux up to Python
    3.13) inherit what it loaded; spawned ones (macOS, and Linux's forkserver from 3.14) load
    from the disk caches it filled, such as a plugin's compiled code, instead of each building
    it at once (and giving its notice once each)."""
    return n_workers > 1


def make_pool(n_workers: int, setup: WorkerSetup) -> Pool | nullcontext[InProcess]:
    """A pool of ``n_workers`` initialised with ``setup`` (in-process when 1)."""
    if n_workers == 1:
        return nullcontext(InProcess(setup))
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
    instead of each loading it again, and no worker builds what it built (a plugin's compiled
    code on first use: once, and its notice given once).
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
    """The results of ``jobs`` run on ``pool`` in runs of :data:`RUN`, in job order; a run's
    error is raised after the results of the scenes before it."""
    left = iter(jobs)
    runs = iter(lambda: tuple(itertools.islice(left, RUN)), ())
    for batch in pool.imap(run_jobs, runs):
        yield from batch.results
        if batch.error is not None and batch.traceback:
            raise batch.error from WorkerTraceback(batch.traceback)
        if batch.error is not None:
            raise batch.error


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
            if kept >= per_horizon:  # surplus of the batch: written, but not kept
                if result.files:
                    shutil.rmtree(scene_dir(setup.root, h, result.row.index), ignore_errors=True)
            elif result.row.stable is False:
                writer.drop(h)
            else:
                writer.add(result)
                kept += 1
                progress.advance()


@dataclass(frozen=True)
class Job:
    """Scene ``index`` at ``horizon``; ``keep_unstable`` False skips writing unstable scenes."""

    horizon: float
    index: int
    keep_unstable: bool = True


@dataclass(frozen=True)
class SceneResult:
    """What a worker reports back: the index row and the files it wrote (relative path, sha256)."""

    row: IndexRow
    files: tuple[tuple[str, str], ...]


@dataclass(frozen=True)
class WorkerSetup:
    """Everything a worker needs, picklable (classes travel by reference).

    Attributes:
        origin: Who supplied the family (a registry entry's origin), for one-line plugin errors.
        spec: The simulator as the config names it (``pymunk:dt=0.0005``, where a refused
            option's value is set): its registered name and the options it is built with;
            ``simulator_origin`` who supplied it.
    """

    root: Path
    seed: int
    config: Any
    family_cls: type
    simulator_cls: type
    images: bool
    origin: str
    spec: SimulatorSpec
    simulator_origin: str
    plugins: tuple[tuple[str, str], ...] = ()
    scenes: int = 0


_SETUP: WorkerSetup | None = None
_STATE: dict[str, Any] = {}


def init_worker(setup: WorkerSetup) -> None:
    """Pool initializer: build the family and simulator once per process.

    A family or simulator whose constructor raises is a :class:`PluginBug` naming its plugin,
    raised by the process's first job (a pool initializer that raises only kills its process,
    which the pool starts again, for ever)."""
    global _SETUP
    _SETUP = setup
    _STATE.clear()
    family = getattr(setup.family_cls, "name", setup.family_cls.__name__)
    simulator = setup.spec.name
    try:
        with blamed(setup.origin, f"creating the scene family {family!r}"):
            _STATE["family"] = setup.family_cls()
        with blamed(setup.simulator_origin, f"creating the simulator {simulator!r}"):
            made = setup.simulator_cls(**setup.spec.options)
            if isinstance(made, ExpectsWork) and setup.scenes:
                made.expect_scenes(setup.scenes)
            _STATE["simulator"] = made
    except BpbError as exc:
        _STATE["broken"] = exc


def worker_signals() -> None:
    """Initializer of a pool process: Ctrl-C left to its parent, SIGTERM at its default.

    Ctrl-C in a terminal reaches the whole process group and the parent stops the pool; a
    worker dying of it mid-job printed a traceback, and its job was never answered (the parent
    waited). SIGTERM is how ``Pool.terminate()`` stops its workers, and a worker must die of it
    at once: a Python-level handler inherited from the parent (a library caller's, or ``bpb
    bench run``'s) only sets a flag, and an idle worker that takes it just before blocking on
    the task queue's lock (which the terminating parent holds) never runs it: the worker waits
    for ever, and so does the parent joining it (1 in 5 paper-size datasets generated under
    such a handler hung at the end).
    """
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # last: once it is ignored, both are set
    if hasattr(signal, "pthread_sigmask"):  # held since the fork (started_pool); now discarded
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def started_pool(start: Callable[[], Pool]) -> Pool:
    """``start()``, a pool whose initializer is :func:`worker_signals`, with Ctrl-C held back
    (blocked) while it starts its workers, and its threads that start any later ones.

    A worker inherits the block, so from its fork until its initializer ignores Ctrl-C it can
    only hold one back, not die of it with a traceback. A Ctrl-C meanwhile reaches this
    process once the pool has started (``KeyboardInterrupt``), and the pool is terminated.
    """
    if not hasattr(signal, "pthread_sigmask"):
        return start()
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        pool = start()
    except BaseException:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)
        raise
    try:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)  # raises a Ctrl-C that came meanwhile
    except BaseException:
        pool.terminate()
        raise
    return pool


def init_pool_worker(setup: WorkerSetup) -> None:
    """Initializer of a pool process: :func:`worker_signals`, then :func:`init_worker`."""
    worker_signals()
    init_worker(setup)
    _STATE["pooled"] = True


def _ready() -> tuple[WorkerSetup, SceneFamily, Simulator]:
    if _SETUP is None:
        raise RuntimeError("init_worker was not called in this process")
    if "broken" in _STATE:
        raise _STATE["broken"]
    return _SETUP, _STATE["family"], _STATE["simulator"]


@dataclass(frozen=True)
class Batch:
    """What a worker reports for a run of jobs: the results of the scenes it finished, in job
    order, and the error that stopped it, if one did (the scenes before it are written and
    listed, as when each scene is its own job), with its traceback's text when a pool process
    raised it (a pickled error loses its traceback)."""

    results: tuple[SceneResult, ...]
    error: Exception | None = None
    traceback: str = ""


class WorkerTraceback(Exception):
    """The traceback of an error a pool process raised, as text: the cause it is raised from."""


def run_jobs(jobs: tuple[Job, ...]) -> Batch:
    """Produce a run of scenes with the process's setup (see :func:`init_worker` and
    :func:`produce`); the first error stops it."""
    results: list[SceneResult] = []
    try:
        for job in jobs:
            results.append(produce(*_ready(), job))
    except Exception as exc:
        text = "".join(traceback.format_exception(exc)) if "pooled" in _STATE else ""
        return Batch(tuple(results), exc, text)
    return Batch(tuple(results))


def calibrate_job(horizon: float) -> tuple[float, Any]:
    """Calibrate one horizon with the process's setup (the family must be ``Calibrating``).

    Raises:
        BadInput: The simulator cannot finish a calibration scene (an event cap overrun, a
            step it refuses), naming the config (its file, once generation adds it), the
            horizon and, for an option's value, where the config sets it.
        PluginBug: The family's ``calibrate_horizon()`` raised anything else, naming its plugin.
    """
    setup, family, simulator = _ready()
    assert isinstance(family, Calibrating), "checked before the pool starts"
    what = f"scene family {family.name!r}: calibrate_horizon({horizon:g})"
    with _finishing(setup, what, f"config: --calibrate: horizon {horizon:g} s"):
        return horizon, family.calibrate_horizon(setup.config, simulator, horizon)


def produce(setup: WorkerSetup, family: SceneFamily, simulator: Simulator, job: Job) -> SceneResult:
    """Make, write and hash one scene; return its row and file hashes.

    Raises:
        BadInput: The config makes a scene the simulator cannot finish.
        WriteRefused: The system refused to write a scene file (names it).
        PluginBug: The family's ``make_scene()`` (or its scene's ``files()``) raised or
            returned something else than it should, naming the family's plugin.
    """
    name = scene_id(job.horizon, job.index)
    what = f"scene family {family.name!r}: make_scene({name!r})"
    with _finishing(setup, what, f"config: scene {name}"):
        scene = family.make_scene(setup.config, simulator, setup.seed, job.horizon, job.index)
    row = IndexRow(name, job.horizon, job.index, *_cells(setup.origin, what, name, family, scene))
    if not (job.keep_unstable or row.stable is not False):
        return SceneResult(row, ())
    files = _files(setup, what, scene)
    folder = scene_dir(setup.root, row.horizon, row.index)
    with writing(folder):
        folder.mkdir(parents=True, exist_ok=True)
    rel = folder.relative_to(setup.root).as_posix()
    for file_name, data in files.items():
        with writing(folder / file_name):  # a full disk, a file size limit: the user's to fix
            (folder / file_name).write_bytes(data)
    return SceneResult(row, tuple((f"{rel}/{n}", sha256_bytes(d)) for n, d in files.items()))


@contextmanager
def _finishing(setup: WorkerSetup, what: str, where: str) -> Iterator[None]:
    """Plugin code under :func:`blamed`; a simulator's own error on a scene (a
    :class:`BpbError` that is neither bad input nor a plugin bug: an event budget overrun, a
    step it refuses) is bad input naming ``where``: the config makes scenes it cannot finish.
    One about an option's value (``dt``) says where that is set: in the simulator the config
    names (``pymunk:dt=...``)."""
    try:
        with blamed(setup.origin, what):
            yield
    except (BadInput, PluginBug):
        raise
    except BpbError as exc:
        said = f"{where}: {exc}; the simulator cannot finish it"
        if exc.option is not None:
            spec, name, option = setup.spec.spec, setup.spec.name, exc.option
            said += (
                f": set {option} in the config's simulator {spec or name!r} ({name}:{option}=...)"
            )
        raise BadInput(said) from None


def _cells(
    origin: str, what: str, name: str, family: SceneFamily, made: Any
) -> tuple[tuple[tuple[str, object], ...], bool | None]:
    """The index cells and stability of a made scene, checked: a :class:`GeneratedScene` named
    as the folder it lands in, whose row holds every index column."""
    with blamed(origin, f"{what}'s scene"):  # its attributes may be properties
        truth, row = getattr(made, "truth", None), getattr(made, "row", None)
        made_id, stable = getattr(truth, "scene_id", None), getattr(truth, "stable", None)
    shaped = isinstance(made_id, str) and stable in (True, False, None)
    if not (shaped and isinstance(row, Mapping) and callable(getattr(made, "files", None))):
        expected = "a bpb_core.GeneratedScene (truth with scene_id and stable, row, files())"
        raise returned(origin, what, type(made).__name__, expected)
    if made_id != name:
        raise PluginBug(
            f"{origin}: {what} made scene {made_id!r}; make_scene must name scene i at "
            "horizon t bpb_core.layout.scene_id(t, i)"
        )
    missing = [column for column in family.index_columns if column not in row]
    if missing:
        raise PluginBug(
            f"{origin}: {what} returned a scene whose row lacks {missing[0]!r} (one of the "
            "family's index_columns)"
        )
    return tuple((column, row[column]) for column in family.index_columns), stable


def _files(setup: WorkerSetup, what: str, made: GeneratedScene) -> dict[str, bytes]:
    """The made scene's ``files()``, checked: file names and their bytes."""
    with blamed(setup.origin, f"{what}'s files()"):
        files = made.files(setup.images)
    if isinstance(files, dict) and all(
        isinstance(k, str) and isinstance(v, bytes) for k, v in files.items()
    ):
        return files
    expected = "a dict of file names (str) and their contents (bytes)"
    raise returned(setup.origin, f"{what}'s files()", type(files).__name__, expected)


def generate_dataset(
    out: str | Path,
    per_horizon: int,
    horizons: Sequence[float],
    seed: int,
    config: Any = None,
    progress: GenerateProgress | None = None,
    *,
    family: str | None = None,
    stable_only: bool = False,
    workers: int | None = None,
    images: bool = True,
    calibrate: bool = False,
    overwrite: bool = False,
    registry: Registry | None = None,
) -> Path:
    """Generate a dataset folder (SPEC section 4 layout) and return its path.

    The folder is built beside ``out`` under a hidden ``.NAME.partial`` name and renamed at the
    end, so an interrupted generation never leaves a folder that looks complete. A generation
    stopped by bad input (a config whose scenes cannot be made) removes that folder; one the
    system refused to write (a full disk) keeps it, as Ctrl-C does, and says so. Either leaves
    a dataset it was to overwrite as it was.

    Args:
        out: Folder to create; it must not exist or be empty (or be a dataset, with
            ``overwrite``).
        per_horizon: Scenes per horizon (1 to 100,000).
        horizons: Horizons in seconds.
        seed: Dataset seed; scene ``i`` at horizon ``t`` is drawn from (seed, t, i).
        config: The family's config object, a mapping of its fields or a JSON/TOML file;
            ``None`` uses the family's defaults.
        progress: Receives progress; nothing is printed.
        family: Scene family plugin (default: the installed default family).
        stable_only: Keep only scenes whose ground truth is stable: unstable draws are skipped
            and further indices drawn until ``per_horizon`` are kept (scene indices then have
            gaps; the dropped count per horizon is in the manifest).
        workers: Processes (default: all cores); 1 runs in this process. With more, where
            workers are forked, this process makes the first scene before they start, so they
            inherit what it loaded (the family's modules and caches stay loaded here too).
        images: Render the family's images.
        calibrate: Recalibrate the family's sampling first (recorded in the manifest).
        overwrite: Replace an existing dataset folder at ``out``.
        registry: Where the family and simulator come from (default: installed plugins).

    Raises:
        BadInput: Bad arguments or config (the message names the file or field).
        WriteRefused: The system refused a write (names the file, and what is left where).
        Interrupted: Ctrl-C stopped it (a ``KeyboardInterrupt`` saying what is left where: the
            scenes listed so far, whole, in the partial folder; an existing ``out`` as it was).
    """
    with _naming_file(config):
        if registry is None:
            from bpb_core.registry import make_registry

            registry = make_registry(warn=False)  # the CLI reports its warnings itself
        name = family or registry.default_family()
        maker = registry.scene_family(name)
        origin = registry.origin("scene_family", name)
        cfg = loaded_config(maker, origin, config)
        if getattr(cfg, "family", maker.name) != maker.name:
            raise BadInput(
                f"config: family: {cfg.family!r}, but the scene family is {maker.name!r}"
            )
        spec = _check_simulator(registry, maker, origin, cfg)
        hs = _check_args(per_horizon, horizons)
        if calibrate and not isinstance(maker, Calibrating):
            raise BadInput(f"--calibrate: the {name} scene family has nothing to calibrate")
        # Fail before touching the disk; with --calibrate, before the slow calibration, without
        # the horizons (it gives them their settings; checked again on its result)
        checked_config(maker, origin, cfg, () if calibrate else hs)
        progress = progress or NoProgress()
        target = Path(out)
        if target.exists() and (not target.is_dir() or any(target.iterdir())):
            is_dataset = (target / MANIFEST).is_file()
            if not (overwrite and is_dataset):
                hint = (
                    "pass overwrite=True (--overwrite)"
                    if is_dataset
                    else "choose a new or empty folder"
                )
                raise BadInput(f"{target}: --out: exists and is not an empty folder; {hint}")
        check_writable_folder(target)
        with partial_folder(target, "bpb generate") as partial:
            try:
                n_workers = max(1, workers or os.cpu_count() or 1)
                setup = worker_setup(registry, name, partial, seed, cfg, images, spec)
                setup = replace(setup, scenes=per_horizon * len(hs))
                calibration = None
                if isinstance(maker, Calibrating) and calibrate:
                    results = run_calibration(n_workers, setup, hs, progress)
                    cfg, calibration = calibrated(maker, origin, cfg, results)
                    checked_config(maker, origin, cfg, hs)
                    setup = replace(setup, config=cfg)
                tallies = new_tallies(maker, origin, cfg, hs)
                writer = DatasetWriter(
                    partial, hs, maker.index_columns, tallies, origin, family_label(maker)
                )
                try:
                    run_scenes(n_workers, setup, writer, hs, per_horizon, stable_only, progress)
                    _write_stats(maker, setup, writer, tallies, progress)
                finally:
                    writer.close()
                writer.write_manifest(
                    _manifest(maker, setup, writer, hs, per_horizon, stable_only, calibration)
                )
            except BadInput:  # the message says what to change; a half-built folder is of no use
                shutil.rmtree(partial, ignore_errors=True)
                raise
            except WriteRefused as exc:  # left as Ctrl-C leaves it; the user may need the space
                raise WriteRefused(f"{exc}; {_left(target, partial)}") from None
            except KeyboardInterrupt:  # the scenes listed so far are whole; say where they are
                raise Interrupted(_left(target, partial)) from None
            if target.exists():
                shutil.rmtree(target)
            partial.rename(target)
        return target


def _left(target: Path, partial: Path) -> str:
    """What an unfinished generation (a write the system refused, a Ctrl-C) leaves, and where."""
    kept = f"{target} is as it was, " if target.exists() else ""
    return (
        f"{kept}the unfinished dataset is left in {partial} (delete it to free its space; "
        "running the command again starts it afresh)"
    )


@contextmanager
def _naming_file(config: Any) -> Iterator[None]:
    """A config error ("config: balls: ...") names the config's file when it came from one."""
    try:
        yield
    except BadInput as exc:
        text = str(exc)
        if isinstance(config, str | Path) and text.startswith("config: "):
            raise BadInput(f"{config}: {text.removeprefix('config: ')}") from None
        raise


def _check_simulator(
    registry: Registry, family: SceneFamily, origin: str, cfg: Any
) -> SimulatorSpec:
    """The simulator spec (``name`` or ``name:key=value,...``) ``cfg`` names; refused, before any
    worker starts and naming the field, when it does not parse, names an unknown simulator, or
    options it does not take or whose values it refuses (it is built once here to see)."""
    spec = parse_spec(simulator_named(family, origin, cfg), "config: simulator")
    try:
        registry.get("simulator", spec.name)
    except UnknownName as exc:
        raise BadInput(f"config: simulator: {exc}") from None
    if spec.options:
        try:
            registry.simulator(spec.name, spec.options)
        except BadInput as exc:
            raise BadInput(f"config: simulator {spec.spec!r}: {exc}") from None
    return spec


def _check_args(per_horizon: int, horizons: Sequence[float]) -> list[float]:
    check_per_horizon(per_horizon, "per_horizon")
    hs = [float(h) for h in horizons]
    if not hs:
        raise BadInput("horizons: give at least one horizon")
    bad = [h for h in hs if not 0 < h < math.inf]
    if bad:
        raise BadInput(f"horizons: must be positive finite seconds, got {bad[0]:g}")
    if len(set(hs)) != len(hs):
        raise BadInput("horizons: a horizon is listed twice")
    return hs


def _write_stats(
    family: SceneFamily,
    setup: WorkerSetup,
    writer: DatasetWriter,
    tallies: Mapping[float, HorizonTally],
    progress: GenerateProgress,
) -> None:
    if not isinstance(family, DrawingStats):
        return
    progress.phase("stats", 1)
    what = f"scene family {family.name!r}: write_stats()"
    with blamed(setup.origin, what):
        written = family.write_stats(setup.root, setup.config, tallies)
    if not isinstance(written, list | tuple) or not all(isinstance(r, str) for r in written):
        expected = "a list of the paths it wrote (str, relative to the dataset folder)"
        raise returned(setup.origin, what, type(written).__name__, expected)
    missing = [rel for rel in written if not (setup.root / rel).is_file()]
    if missing:
        raise PluginBug(
            f"{setup.origin}: {what} returned {missing[0]!r}, which is no file it wrote "
            "in the dataset folder"
        )
    for rel in written:
        writer.add_file(rel)
    progress.advance()


def _manifest(
    family: SceneFamily,
    setup: WorkerSetup,
    writer: DatasetWriter,
    hs: list[float],
    per_horizon: int,
    stable_only: bool,
    calibration: dict[str, Any] | None,
) -> DatasetManifest:
    summary = writer.summary()
    config = {"family": family.name, **setup.config.model_dump(mode="json")}
    return DatasetManifest(
        seed=setup.seed,
        per_horizon=per_horizon,
        horizons=hs,
        stable_only=stable_only,
        images=setup.images,
        scenes=sum(s.scenes for s in summary.values()),
        summary=summary,
        config=config,
        physics=recorded_physics(family, setup.origin, setup.config),
        calibration=calibration,
        plugins=dict(setup.plugins),
        versions=versions(),
    )


# A scene family's generation hooks, called checked as bpb_core.plugin_calls calls others: each
# runs under blamed() and checks what it returns, so a family's mistake is one line naming its
# plugin (PluginBug, exit 3) instead of a traceback, or an error blamed on the manifest or the
# user's config. A BadInput the family raises about the config passes through.


def checked_config(
    family: SceneFamily, origin: str, config: Any, horizons: Sequence[float]
) -> None:
    """``family.check_config(config, horizons)``: its ``BadInput`` passes through.

    Raises:
        PluginBug: It raised anything else, naming ``origin`` (who supplied the family).
    """
    with blamed(origin, f"{family_label(family)}: check_config()"):
        family.check_config(config, horizons)


def recorded_physics(family: SceneFamily, origin: str, config: Any) -> dict[str, Any]:
    """``family.physics(config)``, checked: a dict that JSON can hold (the manifest records it).

    Raises:
        PluginBug: It raised or returned something else, naming ``origin``.
    """
    what = f"{family_label(family)}: physics()"
    with blamed(origin, what):
        physics = family.physics(config)
    return json_values(origin, what, physics, "what dataset.json")


def new_tallies(
    family: SceneFamily, origin: str, config: Any, horizons: Sequence[float]
) -> dict[float, HorizonTally]:
    """A ``family.new_tally(config, h)`` per horizon (none when the family does not tally),
    checked: each has ``add()`` and ``summary()``, which the writer calls next, checked too.

    Raises:
        PluginBug: ``new_tally()`` raised or returned something else, naming ``origin``.
    """
    if not isinstance(family, Tallying):
        return {}
    tallies = {}
    for horizon in horizons:
        what = f"{family_label(family)}: new_tally({horizon:g})"
        with blamed(origin, what):
            tally = family.new_tally(config, horizon)
        if not all(callable(getattr(tally, name, None)) for name in ("add", "summary")):
            expected = "a tally with add(row) and summary()"
            raise returned(origin, what, type(tally).__name__, expected)
        tallies[horizon] = tally
    return tallies


def calibrated(
    family: Calibrating, origin: str, config: Any, results: Mapping[float, Any]
) -> tuple[Any, dict[str, Any]]:
    """``family.apply_calibration(config, results)``, checked: the calibrated config (an
    instance of the family's ``config_model``) and the manifest's record (a dict).

    Raises:
        PluginBug: It raised or returned something else, naming ``origin``.
    """
    what = f"{family_label(family)}: apply_calibration()"
    with blamed(origin, what):
        applied = family.apply_calibration(config, results)
    model = family_model(family, "config_model")
    if isinstance(applied, tuple) and len(applied) == 2:
        new, record = applied
        if (model is None or isinstance(new, model)) and isinstance(record, dict):
            return new, record
    got = type(applied).__name__
    if isinstance(applied, tuple) and len(applied) == 2:
        got = f"({', '.join(type(part).__name__ for part in applied)})"
    expected = "the config" if model is None else model.__name__
    raise returned(origin, what, got, f"({expected}, a dict: the manifest's calibration record)")
