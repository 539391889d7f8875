"""Simulate scene files: the library behind ``bpb simulate``.

Inputs are ``init.json`` files, scene folders holding one, ``final.json`` files (the ``init.json``
beside them is simulated) or dataset folders (every ``h{t}/scene_{i}`` in dataset order). Scenes
are read with the models of the simulator's scene family, and results come back in input order,
one ground truth (the family's ``final.json`` model) per scene. Every user mistake is a
:class:`~bpb_core.errors.BadInput` naming the file and the field, e.g.
``scenes/x.json: <field path>: what is wrong``.
"""

from __future__ import annotations

import contextlib
import functools
import math
import os
import stat
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from bpb_core.capabilities import TruthOfMany
from bpb_core.dataset.generate import check_workers, started_pool, worker_signals
from bpb_core.dataset.manifest import check_simulator
from bpb_core.dataset.reader import DataFolder, open_folder
from bpb_core.errors import BadInput, BpbError, PluginBug
from bpb_core.layout import FINAL, INIT, MANIFEST, scene_dir, scene_places
from bpb_core.plugin_calls import (
    loaded_config,
    simulated_truth,
    simulated_truths,
    simulator_named,
)
from bpb_core.scored_units import object_origin
from bpb_core.simulator_spec import SimulatorSpec, parse_spec
from bpb_core.validated_files import read_model

if TYPE_CHECKING:
    from bpb_core.interfaces import GroundTruth, SceneFamily, Simulator
    from bpb_core.registry import Registry


def scene_files(paths: Iterable[str | Path]) -> list[Path]:
    """The ``init.json`` files named by ``paths``, expanded in input order: a folder holding an
    ``init.json`` stands for it, a dataset folder for its scenes in dataset order, a
    ``final.json`` for the ``init.json`` beside it.

    Raises:
        BadInput: A path does not exist, or is a folder holding no scene.
    """
    found: list[Path] = []
    for name in paths:
        path = Path(name)
        try:
            mode = os.stat(path).st_mode
        except (OSError, ValueError):  # ValueError: a NUL in the name
            raise BadInput(f"{name}: no such file or directory") from None
        if stat.S_ISDIR(mode):
            found.extend(_folder_scenes(path))
        elif path.name == FINAL:
            found.append(path.with_name(INIT))
        else:
            found.append(path)
    return found


def _folder_scenes(folder: Path) -> list[Path]:
    if (folder / INIT).is_file():
        return [folder / INIT]
    found = [scene_dir(folder, horizon, index) / INIT for horizon, index in scene_places(folder)]
    if not found:
        raise BadInput(f"{folder}: no {INIT} and no dataset scene folders (h<t>/scene_<i>) in it")
    return found


MAX_SCENE_BYTES = 10 * 1024 * 1024
"""A scene file larger than this is refused unread past it (``/dev/zero`` is not read for
ever)."""


def read_scene(path: Path, model: type[Any]) -> Any:
    """The scene in ``path``, validated by ``model``; a file, a named pipe or ``/dev/stdin``.

    Raises:
        BadInput: It cannot be read, is larger than :data:`MAX_SCENE_BYTES` or is invalid,
            naming the file (and the field).
    """
    parts: list[bytes] = []
    size = 0
    try:
        with open(path, "rb") as file:
            while size <= MAX_SCENE_BYTES:  # read(MAX_SCENE_BYTES + 1) would allocate that much
                part = file.read(1 << 16)
                if not part:
                    break
                parts.append(part)
                size += len(part)
    except OSError as exc:
        raise BadInput(f"{path}: cannot read: {exc.strerror or exc}") from None
    if size > MAX_SCENE_BYTES:
        raise BadInput(
            f"{path}: larger than {MAX_SCENE_BYTES // (1024 * 1024)} MB, not a scene file"
        )
    return read_model(path, model, b"".join(parts))


def simulate_scene(
    scene: Any,
    simulator: Simulator,
    family: SceneFamily,
    horizon: float | None = None,
    *,
    stability: bool = False,
    origin: str | None = None,
) -> GroundTruth:
    """Ground truth of ``scene`` at ``horizon`` (default: the scene's own) from ``simulator``.

    Raises:
        PluginBug: The family raised or returned something other than its ``truth_model``,
            naming ``origin`` (who supplied it; default: its module).
    """
    who = origin if origin is not None else object_origin(family)
    truth: GroundTruth = simulated_truth(
        family, who, scene, simulator, horizon=horizon, stability=stability
    )
    return truth


@dataclass(frozen=True)
class Prepared:
    """A simulator with its family, resolved once for many scenes, and who supplied the family
    (``Registered.origin``), for one-line plugin errors."""

    simulator: Simulator
    family: SceneFamily
    origin: str
    names: Mapping[str, str] = field(default_factory=dict)
    """How the user set each simulator option, for messages (see :func:`prepare`)."""


def prepare(
    horizon: float | None,
    simulator: str | Simulator | None,
    registry: Registry | None,
    options: Mapping[str, Any] | None,
    files: Sequence[Path] = (),
    names: Mapping[str, str] | None = None,
) -> Prepared:
    """Resolve ``simulator`` (a name or spec with options, ``pymunk:dt=0.0005``, where
    ``options`` win; an object; or ``None``: the simulator the scenes' dataset
    was made with, with the options its config gives it (``options`` win), else the default
    family's) and its scene family: the family of that dataset, which reads the scenes and
    makes their truth as it did when the dataset was generated, whatever family the simulator
    itself is registered for; for loose scene files the simulator's family (else the default
    one). ``names``: how the caller's user sets each option (``{"dt": "--dt"}``), for messages;
    an option from the dataset's config is named there.

    Raises:
        BadInput: A bad horizon, an unknown simulator (one the dataset names but that is not
            installed: naming its ``dataset.json``), one registered for another family than
            the dataset's (unless its config names it), or an option it does not take.
    """
    from bpb_core.registry import make_registry

    if horizon is not None and not 0 < horizon < math.inf:
        raise BadInput(f"--horizon: must be a positive finite number, got {horizon}")
    reg = registry if registry is not None else make_registry()
    given, names = dict(options or {}), dict(names or {})
    if simulator is None:
        family, spec, manifest = _made_with(files, reg)
        if manifest is not None:
            check_simulator(manifest, spec.name, reg, "; or choose one with --simulator")
        where = f"{f'{manifest}: ' if manifest else ''}config: simulator"
        return _built(reg, family, spec, where, given, names)
    if isinstance(simulator, str):
        spec = parse_spec(simulator, "--simulator")
        return _built(reg, _family_for(files, spec.name, reg), spec, "--simulator", given, names)
    name = reg.default_family()
    return Prepared(simulator, reg.scene_family(name), reg.origin("scene_family", name))


def _built(
    reg: Registry,
    family: SceneFamily,
    spec: SimulatorSpec,
    where: str,
    given: dict[str, Any],
    names: dict[str, str],
) -> Prepared:
    """``spec``'s simulator built with its options and ``given`` (which win), each option of the
    spec named in messages as ``where`` sets it (``--simulator 'pymunk:dt=0.5': dt``)."""
    names.update({k: f"{where} {spec.spec!r}: {k}" for k in spec.options if k not in given})
    made = reg.simulator(spec.name, {**spec.options, **given}, names=names)
    return Prepared(made, family, reg.origin("scene_family", family.name), names)


def _made_with(
    files: Sequence[Path], registry: Registry
) -> tuple[SceneFamily, SimulatorSpec, Path | None]:
    """The family of the dataset the first scene file belongs to, the simulator its config
    names with its options and its manifest (the default family, the simulator of its default
    config and ``None`` for loose scene files)."""
    folder = _dataset_of(files, registry)
    if folder is not None:
        return folder.family, folder.simulator_spec(), folder.root / MANIFEST
    family = registry.scene_family(registry.default_family())
    origin = registry.origin("scene_family", family.name)
    named = simulator_named(family, origin, loaded_config(family, origin, None))
    return family, parse_spec(named, "config: simulator"), None


def _dataset_of(files: Sequence[Path], registry: Registry) -> DataFolder | None:
    """The dataset folder the first scene file belongs to, read once (``None``: loose scene
    files)."""
    for folder in list(files[0].parents)[:3] if files else []:
        if (folder / MANIFEST).exists():  # a folder by that name is named as unreadable
            return open_folder(folder, registry)
    return None


def _family_for(files: Sequence[Path], simulator: str, registry: Registry) -> SceneFamily:
    """The family that reads the scenes for ``--simulator``: their dataset's, when they belong
    to one, else the one the simulator is registered for (else the default one).

    Raises:
        BadInput: The simulator is registered for another family than the dataset's, and is
            not the one the dataset's config names (generation paired them).
    """
    simulates = registry.simulator_info(simulator).family
    folder = _dataset_of(files, registry)
    if folder is None:
        return registry.scene_family(simulates or registry.default_family())
    family = folder.family
    if not simulates or simulates == family.name:
        return family
    if folder.simulator_spec().name != simulator:
        raise BadInput(
            f"--simulator {simulator}: simulates {simulates} scenes, but {folder.root} holds "
            f"{family.name} scenes"
        )
    return family


def simulate_paths(
    paths: Iterable[str | Path],
    *,
    horizon: float | None = None,
    simulator: str | Simulator | None = None,
    stability: bool = False,
    registry: Registry | None = None,
    options: Mapping[str, Any] | None = None,
    names: Mapping[str, str] | None = None,
) -> Iterator[GroundTruth]:
    """Simulate every scene named by ``paths`` and yield their final states in input order.

    Args:
        paths: ``init.json``/``final.json`` files, scene folders or dataset folders.
        horizon: Override every scene's own horizon.
        simulator: A registered simulator name, a simulator object, or ``None`` for the one
            the scenes' dataset was made with (the default family's for loose files).
        stability: Also compute the stability annotation of each scene.
        registry: Registry to look the name up in (default: installed plugins).
        options: Options for the simulator (``dt`` for ``pymunk``, ``precision`` for analytic).
        names: How the caller's user sets each option (``{"dt": "--dt"}``), for messages
            (default: as the simulator takes it).

    Raises:
        BadInput: A path does not exist or a scene file is invalid (file and field named).
    """
    files = scene_files(paths)
    run = _Run(prepare(horizon, simulator, registry, options, files, names), horizon, stability)
    for path in files:
        yield run.truth(path)


@dataclass(frozen=True)
class _Run:
    """What one call simulates with (passed to each worker as it starts), and whether scenes go
    to the family in chunks (:class:`~bpb_core.capabilities.TruthOfMany`)."""

    job: Prepared
    horizon: float | None
    stability: bool
    batch: bool = False

    def truth(self, path: Path, scene: Any = None) -> GroundTruth:
        """The ground truth of the scene file ``path`` (``scene``: its scene, read already)."""
        job = self.job
        if scene is None:
            scene = read_scene(path, job.family.scene_model)
        with _naming(path, job.names):
            return simulate_scene(
                scene,
                job.simulator,
                job.family,
                self.horizon,
                stability=self.stability,
                origin=job.origin,
            )

    def lines(self, files: Sequence[Path]) -> tuple[list[str], BadInput | None]:
        """The ``final.json`` lines of ``files``, up to a bad one, and its error."""
        if self.batch:
            return self._batch_lines(files)
        lines: list[str] = []
        for path in files:
            try:
                lines.append(self.truth(path).model_dump_json())
            except BadInput as exc:
                return lines, exc
        return lines, None

    def _batch_lines(self, files: Sequence[Path]) -> tuple[list[str], BadInput | None]:
        """:meth:`lines` with the scenes read first, then simulated by the family at once; when
        that fails on bad input (an event cap overrun), one by one, naming the file."""
        job, scenes, error = self.job, [], None
        for path in files:
            try:
                scenes.append(read_scene(path, job.family.scene_model))
            except BadInput as exc:
                error = exc
                break
        try:
            family = cast("TruthOfMany", job.family)  # see simulate_lines
            truths = simulated_truths(family, job.origin, scenes, job.simulator, self.horizon)
        except PluginBug:
            raise
        except BpbError:
            lines: list[str] = []
            for path, scene in zip(files, scenes, strict=False):
                try:
                    lines.append(self.truth(path, scene).model_dump_json())
                except BadInput as exc:
                    return lines, exc
            return lines, error
        return [truth.model_dump_json() for truth in truths], error


BATCH_MIN = 256
"""Scenes from which they go to a family's batch hook in chunks: it may start slowly (load
compiled code) and pay that back only over many scenes."""
PARALLEL_MIN = 256  # below this many scenes, worker start-up costs more than it saves
CHUNK = 16
"""Scenes read, simulated and written together (and handed to a worker at once). Small, so a
chunk's objects are freed before Python's collector moves them to its oldest generation: each
collection of that generation walks every object the process holds (numba's, pydantic's), and
larger chunks set one off every few hundred scenes (``docs/benchmarks.md``)."""


def simulate_lines(
    paths: Iterable[str | Path],
    *,
    horizon: float | None = None,
    simulator: str | Simulator | None = None,
    stability: bool = False,
    registry: Registry | None = None,
    options: Mapping[str, Any] | None = None,
    workers: int = 0,
    names: Mapping[str, str] | None = None,
) -> Iterator[str]:
    """Like :func:`simulate_paths` but yields each ``final.json`` as one JSON line, in input
    order, using ``workers`` processes (0: all cores when there are at least
    :data:`PARALLEL_MIN` scenes; 1: this process only). A bad file's error is raised after the
    lines of the files before it.

    Workers are forked (POSIX only; elsewhere this runs in-process) after the first chunk of
    scenes is simulated here, so they inherit what it loaded, and get the simulator and family
    of this call as they start.
    """
    if workers < 0:
        raise BadInput(f"--workers: must be 0 (automatic) or more, got {workers}")
    check_workers(workers, least=0)
    files = scene_files(paths)
    job = prepare(horizon, simulator, registry, options, files, names)
    batch = not stability and len(files) >= BATCH_MIN and isinstance(job.family, TruthOfMany)
    run = _Run(job, horizon, stability, batch)
    count = _worker_count(workers, len(files))
    chunks = [files[at : at + CHUNK] for at in range(0, len(files), CHUNK)]
    for chunk in chunks if count <= 1 else chunks[:1]:  # the workers inherit what it loaded
        lines, error = run.lines(chunk)
        yield from lines
        if error is not None:
            raise error
    if count <= 1:
        return
    import multiprocessing

    fork = multiprocessing.get_context("fork")
    start = functools.partial(fork.Pool, count, initializer=_start_worker, initargs=(run,))
    with started_pool(start) as pool:
        for lines, error in pool.imap(_worker_lines, chunks[1:]):
            yield from lines
            if error is not None:
                raise error


_WORKER_RUN: list[_Run] = []
"""In a worker process only: the run its pool was started for (:func:`_start_worker`)."""


def _start_worker(run: _Run) -> None:
    """Initializer of a pool process: Ctrl-C left to the parent, and the call's run kept."""
    worker_signals()
    _WORKER_RUN.append(run)


def _worker_lines(files: Sequence[Path]) -> tuple[list[str], BadInput | None]:
    return _WORKER_RUN[0].lines(files)


def _worker_count(workers: int, scenes: int) -> int:
    import multiprocessing

    if workers == 1 or "fork" not in multiprocessing.get_all_start_methods():
        return 1
    if workers > 1:
        return workers
    return (os.cpu_count() or 1) if scenes >= PARALLEL_MIN else 1


@contextlib.contextmanager
def _naming(path: Path, names: Mapping[str, str]) -> Iterator[None]:
    """Turn a simulator's own error on a scene (an event cap overrun, a step budget) into bad
    input naming the scene file, and the option it is about as ``names`` do (``--dt``); a
    plugin's bug stays one, naming the plugin."""
    try:
        yield
    except PluginBug:
        raise
    except BadInput as exc:
        if str(path) in str(exc):
            raise
        raise BadInput(f"{path}: {exc.naming(names)}") from None
    except BpbError as exc:
        raise BadInput(f"{path}: {exc.naming(names)}") from None
