"""The exact messages a run sends for one scene and task (``bpb prompt``), without sending.

The messages come from the same place as a run's: the task's ``messages()`` on the scene read
with its family's model and, for image input, the family's input image. Images are described
(media type, bytes, SHA-256 as stored in the attempts log), never inlined.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import TYPE_CHECKING

from bpb_core.dataset.hf_import import resolve_data
from bpb_core.dataset.reader import dataset_family
from bpb_core.dataset.scene_entry import check_image
from bpb_core.errors import BadInput
from bpb_core.interfaces import PromptOptions
from bpb_core.layout import INIT, MANIFEST
from bpb_core.model_calls import ImagePart, Message
from bpb_core.plugin_calls import prompt_messages
from bpb_core.validated_files import read_model

if TYPE_CHECKING:
    from bpb_core.registry import Registry


def _scene_file(scene: Path, data: Path | None) -> Path:
    """``init.json`` of ``scene``: a file, a scene folder, or a scene id in ``data``."""
    if data is not None and not scene.exists():
        if not data.is_dir():
            raise BadInput(f"{data}: --data: no such dataset folder")
        data = resolve_data(data)  # a Hugging Face export opens as the folder it came from
        found = [p for p in sorted(data.glob(f"h*/scene_*/{INIT}")) if _id(p) == str(scene)]
        if not found:
            raise BadInput(f"{data}: --data: no scene with id {str(scene)!r} (like h1_0000)")
        return found[0]
    if scene.is_dir():
        scene = scene / INIT
    if not scene.is_file():
        raise BadInput(f"{scene}: no such scene file (give init.json, its folder, or an id)")
    return scene


def _id(init: Path) -> str:
    horizon, index = init.parent.parent.name, init.parent.name.removeprefix("scene_")
    return f"{horizon}_{index}"


def _dataset_root(init: Path) -> Path:
    for folder in list(init.parents)[:3]:
        if (folder / MANIFEST).is_file():
            return folder
    return init.parent


def preview_messages(
    scene: Path,
    task: str,
    options: PromptOptions,
    registry: Registry,
    data: Path | None = None,
) -> tuple[Message, ...]:
    """The messages ``task`` sends about ``scene`` under ``options``.

    Raises:
        BadInput: No such scene, an invalid scene file, an unknown task, a task of another
            scene family, or a missing or damaged image for image input.
    """
    init = _scene_file(scene, data)
    family = dataset_family(None, _dataset_root(init), registry)
    asks = registry.task_info(task).family
    if asks and asks != family.name:
        raise BadInput(f"--task: {task} asks about {asks} scenes, not {family.name} scenes")
    value = read_model(init, family.scene_model)
    image = None
    if options.input_mode != "state":
        if family.input_image is None:
            raise BadInput(f"{init.parent}: the {family.name} family has no images")
        path = init.parent / family.input_image
        try:
            image = path.read_bytes()
        except OSError:
            raise BadInput(f"{path}: missing") from None
        check_image(path, image)
    return prompt_messages(
        registry.task(task), registry.origin("task", task), value, image, options
    )


def describe_image(part: ImagePart) -> str:
    """``[image: image/png, 48,213 bytes, sha256 3fa2...]``: an image part, not its bytes."""
    digest = hashlib.sha256(part.data).hexdigest()
    return f"[image: {part.media_type}, {len(part.data):,} bytes, sha256 {digest}]"
