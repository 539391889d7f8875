"""One scene from seed to files: the family makes it, the worker writes and hashes it.

Runs in the worker processes of :func:`bpb_core.dataset.generate.generate_dataset` (and
in-process for ``workers=1``). Each call writes one scene folder and returns a small
:class:`SceneResult`, so nothing accumulates in memory however large the dataset is.
"""

from __future__ import annotations

import shutil
import signal
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.capabilities import Calibrating
from bpb_core.dataset.manifest import IndexRow, sha256_bytes
from bpb_core.errors import BadInput, BpbError, PluginBug, blamed, writing
from bpb_core.interfaces import GeneratedScene, SceneFamily, Simulator
from bpb_core.layout import scene_dir, scene_id

if TYPE_CHECKING:
    from multiprocessing.pool import Pool


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

    @property
    def written(self) -> bool:
        return bool(self.files)


@dataclass(frozen=True)
class WorkerSetup:
    """Everything a worker needs, picklable (classes travel by reference).

    Attributes:
        origin: Who supplied the family (a registry entry's origin), for one-line plugin errors.
        options: Keyword options the simulator is built with.
        simulator: The simulator's registered name; ``simulator_origin`` who supplied it
            (default: ``origin``); ``simulator_spec`` how the config names it with its options
            (``pymunk:dt=0.0005``), where a refused option's value is set.
    """

    root: Path
    seed: int
    config: Any
    family_cls: type
    simulator_cls: type
    images: bool
    origin: str
    plugins: tuple[tuple[str, str], ...] = ()
    options: tuple[tuple[str, Any], ...] = ()
    simulator: str = ""
    simulator_origin: str = ""
    simulator_spec: str = ""


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
    simulator = setup.simulator or setup.simulator_cls.__name__
    try:
        with blamed(setup.origin, f"creating the scene family {family!r}"):
            _STATE["family"] = setup.family_cls()
        with blamed(
            setup.simulator_origin or setup.origin, f"creating the simulator {simulator!r}"
        ):
            _STATE["simulator"] = setup.simulator_cls(**dict(setup.options))
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


def _ready() -> tuple[WorkerSetup, SceneFamily, Simulator]:
    if _SETUP is None:
        raise RuntimeError("init_worker was not called in this process")
    if "broken" in _STATE:
        raise _STATE["broken"]
    return _SETUP, _STATE["family"], _STATE["simulator"]


def run_job(job: Job) -> SceneResult:
    """Produce one scene with the process's setup (see :func:`init_worker` and :func:`produce`)."""
    return produce(*_ready(), job)


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
            spec, name, option = setup.simulator_spec, setup.simulator, exc.option
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
        raise PluginBug(
            f"{origin}: {what} returned {type(made).__name__}; expected a "
            "bpb_core.GeneratedScene (truth with scene_id and stable, row, files())"
        )
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
    raise PluginBug(
        f"{setup.origin}: {what}'s files() returned {type(files).__name__}; expected a dict "
        "of file names (str) and their contents (bytes)"
    )


def remove_scene(root: Path, horizon: float, index: int) -> None:
    """Delete a scene folder written by a worker but not kept (``--stable-only`` surplus)."""
    shutil.rmtree(scene_dir(root, horizon, index), ignore_errors=True)
