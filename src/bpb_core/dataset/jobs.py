"""Generation jobs: one scene from seed to files, and their scheduling on a process pool.

A worker (a pool process, or this one for ``workers=1``) asks the family for a scene, writes
its folder and returns a small :class:`SceneResult`, so nothing accumulates in memory however
large the dataset is. Results come back in job order (``imap``), so the streamed index and
checksums are in scene order however many workers run.
"""

from __future__ import annotations

import itertools
import os
import shutil
import signal
import traceback
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass
from multiprocessing.pool import Pool
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from bpb_core.capabilities import Calibrating, ExpectsWork
from bpb_core.dataset.manifest import DatasetWriter, IndexRow, sha256_bytes
from bpb_core.errors import BadInput, BpbError, PluginBug, blamed, writing
from bpb_core.interfaces import GeneratedScene, SceneFamily, Simulator
from bpb_core.layout import scene_dir, scene_id
from bpb_core.plugin_calls import returned, simulator_named
from bpb_core.simulator_spec import parse_spec

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
