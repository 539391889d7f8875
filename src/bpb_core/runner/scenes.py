"""What a run asks: the dataset's scene family, its tasks, and the scenes selected, read lazily
from the dataset folder.

A run's tasks default to the default tasks of the dataset's family; a task that asks about
another family's scenes is bad input, named with both families. The runner asks about
``init.json`` (and the family's input image, for image input) and never hands ground truth to an
adapter; it only reads each selected scene's ground truth once before the first call
(in :func:`asking`), so a run that could not be scored sends nothing.
"""

from __future__ import annotations

import dataclasses
import hashlib
import random
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.dataset.manifest import check_unedited
from bpb_core.dataset.reader import (
    DataFolder,
    check_image,
    check_recorded,
    dataset_keys,
    open_folder,
    read_scene_files,
    read_scene_model,
)
from bpb_core.errors import BadInput
from bpb_core.layout import INIT, MANIFEST, SceneKey, iter_scene_keys, select_keys
from bpb_core.runner.options import RunOptions, check_options

if TYPE_CHECKING:
    from bpb_core.interfaces import SceneFamily, Task
    from bpb_core.registry import Registry


# the hint of a run that has no images to show, in the library's and the CLI's terms
STATE = "use input mode 'state' (--input-mode state)"


@dataclass(frozen=True)
class SceneRef:
    """A scene of the dataset, not yet loaded."""

    key: SceneKey
    folder: Path
    family: SceneFamily

    @property
    def scene_id(self) -> str:
        return self.key.scene_id

    def load(self) -> Any:
        """Read and validate ``init.json`` with the family's scene model.

        Raises:
            BadInput: The file is missing, invalid (names the file and the field) or changed
                after generation (:mod:`bpb_core.dataset.reader`).
        """
        return read_scene_model(self.folder / INIT, self.family.scene_model)

    def image(self) -> bytes:
        """The bytes of the family's input image.

        Raises:
            BadInput: The image is missing (image input modes need it), truncated, damaged or
                changed after generation.
        """
        name = self.family.input_image
        if name is None:
            raise BadInput(
                f"{self.folder}: the {self.family.name} scene family has no images; {STATE}"
            )
        path = self.folder / name
        try:
            data = path.read_bytes()
        except OSError:
            raise BadInput(f"{path}: missing; {STATE} for text-only runs") from None
        check_image(path, data)
        check_recorded(path, data)
        return data


def check_images(folder: DataFolder, refs: Sequence[SceneRef], input_mode: str) -> None:
    """Refuse image input (any ``input_mode`` but ``state``) on a dataset without the family's
    input images, before the run folder is made: one generated with ``--no-images`` (its
    manifest's ``images`` is false), of a family that renders none, or missing a selected
    scene's image. Only whether each file is there is checked here; each image is read and
    checked when it is sent.

    Raises:
        BadInput: One line naming the dataset (or the missing file) and ``--input-mode state``.
    """
    if input_mode == "state":
        return
    data, recorded = folder.root, folder.recorded
    if recorded is not None and recorded.get("images") is False:
        raise BadInput(
            f"{data}: generated with --no-images ({MANIFEST}: images: false), so it has no "
            f"images to show; {STATE}"
        )
    for ref in refs:
        name = ref.family.input_image
        if name is None:
            raise BadInput(f"{data}: the {ref.family.name} scene family has no images; {STATE}")
        if not (ref.folder / name).is_file():
            raise BadInput(f"{ref.folder / name}: missing; {STATE} for text-only runs")


def dataset_hash(folder: DataFolder) -> str:
    """A hash identifying the dataset: the manifest's own when it records one, else a digest of
    ``dataset.json`` (or, without a manifest, of every ``init.json``)."""
    data, recorded = folder.root, folder.recorded
    if recorded is not None and folder.digest is not None:
        value = recorded.get("dataset_hash")
        return value if isinstance(value, str) and value else folder.digest
    digest = hashlib.sha256()
    for key in iter_scene_keys(data):
        path = key.dir(data) / INIT
        if path.exists():
            digest.update(path.read_bytes())
    return digest.hexdigest()


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
    if not folder.root.is_dir():
        raise BadInput(f"{folder.root}: --data: not a dataset folder")
    keys = select_keys(dataset_keys(folder.root), options.horizons, options.limit)
    if not keys:
        raise BadInput(
            f"{folder.root}: --data: no scenes (h*/scene_*/init.json) match the selection"
        )
    scenes = _chosen([SceneRef(key, key.dir(folder.root), family) for key in keys], options)
    for ref in scenes:  # read as scoring will: a damaged final.json stops the run up front
        read_scene_files(ref.folder, family.scene_model, family.truth_model)
    simulator = folder.simulator()
    check_unedited(folder.root / MANIFEST, folder.recorded)  # after those naming a field
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
