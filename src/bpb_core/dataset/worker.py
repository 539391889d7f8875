"""One scene from seed to files: sample, simulate, annotate, render, write, hash.

Runs in the worker processes of :func:`bpb_core.dataset.generate_dataset` (and in-process for
``workers=1``). Each call writes one scene folder and returns a small :class:`SceneResult`, so
nothing accumulates in memory however large the dataset is.
"""

from __future__ import annotations

import math
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.dataset.manifest import IndexRow, sha256_bytes
from bpb_core.layout import FINAL, INIT, scene_dir
from bpb_core.outcome import CUE_ID, Outcome, final_state
from bpb_core.scene import FinalState, Scene, Stability

if TYPE_CHECKING:
    from bpb_tasks.billiards.calibrate import Calibration
    from bpb_tasks.billiards.config import DatasetConfig


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
    """Everything a worker needs, picklable (classes travel by reference)."""

    root: Path
    seed: int
    config: DatasetConfig
    family_cls: type
    simulator_cls: type
    simulator_name: str
    images: bool
    plugins: tuple[tuple[str, str], ...] = ()


_SETUP: WorkerSetup | None = None
_STATE: dict[str, Any] = {}


def init_worker(setup: WorkerSetup) -> None:
    """Pool initializer: build the family and simulator once per process."""
    global _SETUP
    _SETUP = setup
    _STATE["family"] = setup.family_cls()
    _STATE["simulator"] = setup.simulator_cls()


def run_job(job: Job) -> SceneResult:
    """Produce one scene with the process's setup (see :func:`init_worker`)."""
    if _SETUP is None:
        raise RuntimeError("init_worker was not called in this process")
    return produce(_SETUP, _STATE["family"], _STATE["simulator"], job)


def calibrate_job(horizon: float) -> Calibration:
    """Calibrate the cue-speed range of one horizon with the process's setup."""
    from bpb_tasks.billiards.calibrate import calibrate_horizon

    if _SETUP is None:
        raise RuntimeError("init_worker was not called in this process")
    return calibrate_horizon(horizon, _SETUP.config, _STATE["simulator"])


def simulate_scene(
    setup: WorkerSetup, family: Any, simulator: Any, horizon: float, index: int
) -> tuple[Scene, Outcome, FinalState]:
    """Sample scene ``index`` at ``horizon``, simulate it and annotate its stability."""
    from bpb_tasks.billiards.sampler import scene_rng

    scene: Scene = family.sample(
        scene_rng(setup.seed, horizon, index), horizon, index, setup.config
    )
    outcome: Outcome = simulator.run(scene)
    final = final_state(scene, outcome, setup.simulator_name)
    stability = annotate(scene, outcome, setup.config.stability_delta, simulator)
    return scene, outcome, final.model_copy(update={"stability": stability})


def annotate(scene: Scene, outcome: Outcome, delta: float, simulator: Any) -> Stability:
    """The stability annotation (re-simulates perturbed copies with the same simulator)."""
    from bpb_tasks.simulators.stability import annotate as physics_annotate

    result: Stability = physics_annotate(scene, outcome, delta=delta, simulator=simulator)
    return result


def produce(setup: WorkerSetup, family: Any, simulator: Any, job: Job) -> SceneResult:
    """Sample, simulate, render and write one scene; return its row and file hashes."""
    scene, outcome, final = simulate_scene(setup, family, simulator, job.horizon, job.index)
    row = index_row(scene, outcome, final, job.index)
    if not job.keep_unstable and row.stable is False:
        return SceneResult(row, ())
    blobs: dict[str, bytes] = {
        INIT: (scene.model_dump_json(indent=2) + "\n").encode(),
        FINAL: (final.model_dump_json(indent=2) + "\n").encode(),
    }
    if setup.images:
        from bpb_tasks.billiards.render import render_pngs

        blobs.update(render_pngs(scene, outcome, setup.config))
    folder = scene_dir(setup.root, job.horizon, job.index)
    folder.mkdir(parents=True, exist_ok=True)
    rel = folder.relative_to(setup.root).as_posix()
    files = []
    for name, data in blobs.items():
        (folder / name).write_bytes(data)
        files.append((f"{rel}/{name}", sha256_bytes(data)))
    return SceneResult(row, tuple(files))


def index_row(scene: Scene, outcome: Outcome, final: FinalState, index: int) -> IndexRow:
    """The ``index.csv`` row of a simulated scene."""
    vx, vy = scene.ball(CUE_ID).vel
    angle = math.degrees(math.atan2(vy, vx)) % 360.0
    contacts = sorted(outcome.cue_contacts())
    pocketed = sorted(i for i, p in outcome.positions.items() if p is None)
    return IndexRow(
        scene_id=scene.scene_id,
        horizon=scene.horizon,
        index=index,
        cue_speed=round(math.hypot(vx, vy), 6),
        cue_angle_deg=round(angle, 6),
        cue_collision=bool(contacts),
        cue_contacts=" ".join(map(str, contacts)),
        cue_walls=" ".join(q.wall for q in final.q2 if q.answer == "T"),
        pocketed=" ".join(map(str, pocketed)),
        events=len(outcome.events),
        stable=None if final.stability is None else final.stability.stable,
    )


def remove_scene(root: Path, horizon: float, index: int) -> None:
    """Delete a scene folder written by a worker but not kept (``--stable-only`` surplus)."""
    shutil.rmtree(scene_dir(root, horizon, index), ignore_errors=True)
