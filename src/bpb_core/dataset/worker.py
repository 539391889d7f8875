"""One scene from seed to files: the family makes it, the worker writes and hashes it.

Runs in the worker processes of :func:`bpb_core.dataset.generate.generate_dataset` (and
in-process for ``workers=1``). Each call writes one scene folder and returns a small
:class:`SceneResult`, so nothing accumulates in memory however large the dataset is.
"""

from __future__ import annotations

import shutil
import signal
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bpb_core.capabilities import Calibrating
from bpb_core.dataset.manifest import IndexRow, sha256_bytes
from bpb_core.errors import BadInput, BpbError
from bpb_core.interfaces import SceneFamily, Simulator
from bpb_core.layout import scene_dir, scene_id


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
        options: Keyword options the simulator is built with.
    """

    root: Path
    seed: int
    config: Any
    family_cls: type
    simulator_cls: type
    images: bool
    plugins: tuple[tuple[str, str], ...] = ()
    options: tuple[tuple[str, Any], ...] = ()


_SETUP: WorkerSetup | None = None
_STATE: dict[str, Any] = {}


def init_worker(setup: WorkerSetup) -> None:
    """Pool initializer: build the family and simulator once per process."""
    global _SETUP
    _SETUP = setup
    _STATE["family"] = setup.family_cls()
    _STATE["simulator"] = setup.simulator_cls(**dict(setup.options))


def init_pool_worker(setup: WorkerSetup) -> None:
    """Initializer of a pool process: :func:`init_worker`, and SIGINT ignored. Ctrl-C in a
    terminal reaches the whole process group and the parent stops the pool; a worker dying of
    it mid-scene printed a traceback, and its scene was never answered (the parent waited)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    init_worker(setup)


def _ready() -> tuple[WorkerSetup, SceneFamily, Simulator]:
    if _SETUP is None:
        raise RuntimeError("init_worker was not called in this process")
    return _SETUP, _STATE["family"], _STATE["simulator"]


def run_job(job: Job) -> SceneResult:
    """Produce one scene with the process's setup (see :func:`init_worker`)."""
    setup, family, simulator = _ready()
    return produce(setup, family, simulator, job)


def calibrate_job(horizon: float) -> tuple[float, Any]:
    """Calibrate one horizon with the process's setup (the family must be ``Calibrating``)."""
    setup, family, simulator = _ready()
    assert isinstance(family, Calibrating), "checked before the pool starts"
    return horizon, family.calibrate_horizon(setup.config, simulator, horizon)


def produce(setup: WorkerSetup, family: SceneFamily, simulator: Simulator, job: Job) -> SceneResult:
    """Make, write and hash one scene; return its row and file hashes."""
    name = scene_id(job.horizon, job.index)
    try:
        made = family.make_scene(setup.config, simulator, setup.seed, job.horizon, job.index)
    except BadInput:
        raise
    except BpbError as exc:  # e.g. an event budget overrun: the config makes unfinishable scenes
        raise BadInput(f"config: scene {name}: {exc}; the simulator cannot finish it") from None
    if made.truth.scene_id != name:
        raise BpbError(
            f"scene family {family.name!r}: made scene {made.truth.scene_id!r} for {name!r}; "
            "make_scene must name scene i at horizon t bpb_core.layout.scene_id(t, i)"
        )
    values = tuple((column, made.row[column]) for column in family.index_columns)
    row = IndexRow(name, job.horizon, job.index, values, made.truth.stable)
    if not job.keep_unstable and row.stable is False:
        return SceneResult(row, ())
    folder = scene_dir(setup.root, job.horizon, job.index)
    folder.mkdir(parents=True, exist_ok=True)
    rel = folder.relative_to(setup.root).as_posix()
    files = []
    for file_name, data in made.files(setup.images).items():
        (folder / file_name).write_bytes(data)
        files.append((f"{rel}/{file_name}", sha256_bytes(data)))
    return SceneResult(row, tuple(files))


def remove_scene(root: Path, horizon: float, index: int) -> None:
    """Delete a scene folder written by a worker but not kept (``--stable-only`` surplus)."""
    shutil.rmtree(scene_dir(root, horizon, index), ignore_errors=True)
