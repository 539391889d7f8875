"""Simulate scene files: the library behind ``bpb simulate``.

Inputs are ``init.json`` files, scene folders holding one, ``final.json`` files (the ``init.json``
beside them is simulated) or dataset folders (every ``h{t}/scene_{i}`` in dataset order). Results
come back in input order, one :class:`~bpb_core.scene.FinalState` per scene. Every user mistake
is a :class:`~bpb_core.errors.BadInput` naming the file and the field, e.g.
``scenes/x.json: balls[2].pos: ball 2 at [2.5, 0.4] is off the table``.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.errors import BadInput
from bpb_core.layout import FINAL, INIT, iter_scene_keys
from bpb_core.model_files import read_model
from bpb_core.outcome import final_state
from bpb_core.scene import FinalState, Scene

if TYPE_CHECKING:
    from bpb_core.interfaces import Simulator
    from bpb_core.registry import Registry


def scene_files(paths: Iterable[str | Path]) -> list[Path]:
    """The ``init.json`` files named by ``paths``, expanded in input order."""
    files: list[Path] = []
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            files.extend(_folder_scenes(path))
        elif path.is_file():
            files.append(path.with_name(INIT) if path.name == FINAL else path)
        else:
            raise BadInput(f"{path}: no such file or directory")
    return files


def _folder_scenes(folder: Path) -> list[Path]:
    if (folder / INIT).is_file():
        return [folder / INIT]
    found = [key.dir(folder) / INIT for key in iter_scene_keys(folder)]
    if not found:
        raise BadInput(f"{folder}: no {INIT} and no dataset scene folders (h<t>/scene_<i>) in it")
    return found


def load_scene(path: Path) -> Scene:
    """Read and validate one ``init.json``; errors name the file and field."""
    return read_model(path, Scene)


def simulate_scene(
    scene: Scene,
    simulator: Simulator,
    horizon: float | None = None,
    *,
    stability: bool = False,
) -> FinalState:
    """Ground truth of ``scene`` at ``horizon`` (default: the scene's own) from ``simulator``."""
    end = scene.horizon if horizon is None else horizon
    outcome = simulator.run(scene, end)
    final = final_state(scene, outcome, simulator=getattr(simulator, "name", "unknown"))
    if stability:
        from bpb_tasks.simulators.stability import annotate

        final = final.model_copy(
            update={"stability": annotate(scene, outcome, simulator=simulator)}
        )
    return final


def make_simulator(
    name: str = "analytic", registry: Registry | None = None, **options: Any
) -> Simulator:
    """The simulator plugin ``name`` built with ``options`` (unknown options are bad input)."""
    from bpb_core.registry import make_registry

    reg = registry if registry is not None else make_registry()
    factory = reg.load("simulator", name)
    try:
        return factory(**options)  # type: ignore[no-any-return]
    except TypeError as exc:
        given = ", ".join(f"--{k}" for k in options)
        raise BadInput(f"simulator {name!r}: does not accept {given}: {exc}") from None


def simulate_paths(
    paths: Iterable[str | Path],
    *,
    horizon: float | None = None,
    simulator: str | Simulator = "analytic",
    stability: bool = False,
    registry: Registry | None = None,
    options: Mapping[str, Any] | None = None,
) -> Iterator[FinalState]:
    """Simulate every scene named by ``paths`` and yield their final states in input order.

    Args:
        paths: ``init.json``/``final.json`` files, scene folders or dataset folders.
        horizon: Override every scene's own horizon.
        simulator: A registered simulator name or a simulator object.
        stability: Also compute the stability annotation of each scene.
        registry: Registry to look the name up in (default: installed plugins).
        options: Options for the simulator (``dt`` for ``pymunk``, ``precision`` for analytic).

    Raises:
        BadInput: A path does not exist or a scene file is invalid (file and field named).
    """
    sim = _prepare(horizon, simulator, registry, options)
    for path in scene_files(paths):
        yield simulate_scene(load_scene(path), sim, horizon, stability=stability)


_JOB: tuple[Simulator, float | None, bool] | None = None  # set before forking workers
PARALLEL_MIN = 256  # below this many scenes, worker start-up costs more than it saves


def simulate_lines(
    paths: Iterable[str | Path],
    *,
    horizon: float | None = None,
    simulator: str | Simulator = "analytic",
    stability: bool = False,
    registry: Registry | None = None,
    options: Mapping[str, Any] | None = None,
    workers: int = 0,
) -> Iterator[str]:
    """Like :func:`simulate_paths` but yields each ``final.json`` as one JSON line, in input
    order, using ``workers`` processes (0: all cores when there are at least
    :data:`PARALLEL_MIN` scenes; 1: this process only).

    Workers are forked (POSIX only) and inherit the simulator; elsewhere this runs in-process.
    """
    global _JOB
    sim = _prepare(horizon, simulator, registry, options)
    files = scene_files(paths)
    count = _worker_count(workers, len(files))
    _JOB = (sim, horizon, stability)
    if count <= 1:
        yield from map(_line, files)
        return
    import multiprocessing

    with multiprocessing.get_context("fork").Pool(count) as pool:
        yield from pool.imap(_line, files, chunksize=max(16, min(256, len(files) // (8 * count))))


def _prepare(
    horizon: float | None,
    simulator: str | Simulator,
    registry: Registry | None,
    options: Mapping[str, Any] | None,
) -> Simulator:
    if horizon is not None and not horizon > 0:
        raise BadInput(f"--horizon: must be positive, got {horizon}")
    if isinstance(simulator, str):
        return make_simulator(simulator, registry, **dict(options or {}))
    return simulator


def _worker_count(workers: int, scenes: int) -> int:
    import multiprocessing
    import os

    if workers == 1 or "fork" not in multiprocessing.get_all_start_methods():
        return 1
    if workers > 1:
        return workers
    return (os.cpu_count() or 1) if scenes >= PARALLEL_MIN else 1


def _line(path: Path) -> str:
    assert _JOB is not None
    sim, horizon, stability = _JOB
    return simulate_scene(load_scene(path), sim, horizon, stability=stability).model_dump_json()
