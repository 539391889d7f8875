"""What a run asks: the dataset's scene family, its tasks, and the scenes selected.

A run's tasks default to the default tasks of the dataset's family; a task that asks about
another family's scenes is bad input, named with both families.
"""

from __future__ import annotations

import dataclasses
import random
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from bpb_core.dataset.reader import DataFolder, open_folder
from bpb_core.errors import BadInput
from bpb_core.runner.options import RunOptions, check_options
from bpb_core.runner.scenes import SceneRef, check_manifest, check_truth, select_scenes

if TYPE_CHECKING:
    from bpb_core.interfaces import SceneFamily, Task
    from bpb_core.registry import Registry


@dataclass(frozen=True)
class Asking:
    """The family, the options with their tasks resolved, the task objects, the scenes, and
    the simulator the dataset's ground truth comes from (for offline baselines)."""

    family: SceneFamily
    options: RunOptions
    tasks: dict[str, Task]
    scenes: list[SceneRef]
    simulator: str
    folder: DataFolder


def asking(data: Path | DataFolder, options: RunOptions, registry: Registry) -> Asking:
    """Resolve what a run on ``data`` (read here when it is a path) with ``options`` asks.

    Raises:
        BadInput: A bad option, not a dataset, a ``dataset.json`` edited after generation, an
            unknown task, a task of another family, or a selected scene whose ``init.json`` or
            ``final.json`` is missing or invalid.
    """
    check_options(options)
    folder = open_folder(data, registry)
    family = folder.family
    names = options.tasks or tuple(registry.tasks_for(family.name, default_only=True))
    if not names:
        raise BadInput(f"--tasks: no installed task asks about {family.name} scenes")
    for name in names:
        asks = registry.task_info(name).family
        if asks and asks != family.name:
            raise BadInput(
                f"--tasks: {name} asks about {asks} scenes, but {folder.root} holds "
                f"{family.name} scenes"
            )
    resolved = dataclasses.replace(options, tasks=tuple(names))
    tasks = {name: registry.task(name) for name in names}
    scenes = _chosen(select_scenes(folder, options.horizons, options.limit), options)
    check_truth(scenes)
    simulator = folder.simulator()
    check_manifest(folder)  # after the checks that name a field, which say more
    return Asking(family, resolved, tasks, scenes, simulator, folder)


def _chosen(refs: list[SceneRef], options: RunOptions) -> list[SceneRef]:
    """The scenes ``--scenes`` names, then a seeded ``--sample`` of them (dataset order kept).

    Raises:
        BadInput: An id not among the selected scenes, or a sample larger than the selection.
    """
    if options.scenes is not None:
        by_id = {ref.scene_id: ref for ref in refs}
        missing = [s for s in options.scenes if s not in by_id]
        if missing:
            raise BadInput(
                f"--scenes: {missing[0]!r} is not a scene of the selection (ids look like "
                f"{refs[0].scene_id}; --horizons and --limit apply first)"
            )
        wanted = set(options.scenes)
        refs = [ref for ref in refs if ref.scene_id in wanted]
    if options.sample is not None:
        if options.sample > len(refs):
            raise BadInput(
                f"--sample: {options.sample} is more than the {len(refs)} scenes selected"
            )
        rng = random.Random(f"bpb-sample:{options.seed}")
        keep = set(rng.sample(range(len(refs)), options.sample))
        refs = [ref for i, ref in enumerate(refs) if i in keep]
    return refs
