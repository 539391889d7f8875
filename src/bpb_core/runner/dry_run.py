"""What a run would send, without sending it: the calls and tokens of a run (``bpb run
--dry-run``) and the exact messages of one scene and task (``bpb prompt``).

The token estimate is the adapter's own when it can give one (:class:`Estimating`: the
provider's tokenizer and image rule, and the input cost); otherwise prompt characters / 4 plus
an image estimate from the PNG size (OpenAI's tile rule: 85 + 170 per 512-pixel tile after
scaling to fit 2048x768). It is a planning figure, not a bill: output tokens are not included.

The messages of ``bpb prompt`` come from the same place as a run's: the task's ``messages()`` on
the scene read with its family's model and, for image input, the family's input image. Images
are described (media type, bytes, SHA-256 as stored in the attempts log), never inlined.
"""

from __future__ import annotations

import hashlib
import itertools
import math
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from bpb_core.capabilities import Estimating
from bpb_core.dataset.hf_import import resolve_data
from bpb_core.dataset.reader import dataset_family
from bpb_core.dataset.scene_entry import check_image
from bpb_core.errors import BadInput
from bpb_core.interfaces import PromptOptions
from bpb_core.layout import INIT, MANIFEST
from bpb_core.model_calls import ImagePart, Message, TextPart
from bpb_core.plugin_calls import estimated_input, prompt_messages
from bpb_core.run_folder import completed_epochs
from bpb_core.runner.options import RunOptions
from bpb_core.runner.scenes import asking, check_images
from bpb_core.scored_units import object_origin
from bpb_core.validated_files import read_model

if TYPE_CHECKING:
    from bpb_core.dataset.reader import DataFolder
    from bpb_core.registry import Registry


@dataclass
class DryRun:
    """Calls a run would make and their estimated input tokens, per task.

    Attributes:
        calls: Calls to send per task (pairs already complete are not counted).
        done: Pairs already complete per task.
        input_tokens: Estimated input tokens per task (first attempts only).
        input_cost: Estimated input cost in USD per task (``None``: no price known, or the
            adapter cannot estimate).
    """

    calls: dict[str, int] = field(default_factory=dict)
    done: dict[str, int] = field(default_factory=dict)
    input_tokens: dict[str, int] = field(default_factory=dict)
    input_cost: dict[str, float | None] = field(default_factory=dict)

    def add(self, task: str, tokens: int, cost: float | None) -> None:
        """Count one call of ``task``."""
        self.calls[task] = self.calls.get(task, 0) + 1
        self.input_tokens[task] = self.input_tokens.get(task, 0) + tokens
        before = self.input_cost.get(task, 0.0)
        self.input_cost[task] = None if before is None or cost is None else before + cost


def image_tokens(png: bytes) -> int:
    """Estimated tokens of a PNG image (OpenAI high-detail tile rule); 765 if unreadable."""
    if len(png) < 24 or png[:8] != b"\x89PNG\r\n\x1a\n":
        return 765
    width, height = struct.unpack(">II", png[16:24])
    scale = min(1.0, 2048 / max(width, height))
    width, height = width * scale, height * scale
    scale = min(1.0, 768 / min(width, height))
    tiles = math.ceil(width * scale / 512) * math.ceil(height * scale / 512)
    return int(85 + 170 * tiles)


def dry_run(
    data: Path | DataFolder,
    run_dir: Path,
    options: RunOptions,
    registry: Registry,
    adapter: object = None,
    origin: str | None = None,
) -> DryRun:
    """Count the calls and estimate the input tokens (and, when ``adapter`` can estimate, the
    input cost) of a run without sending anything. ``origin`` is who supplied ``adapter``
    (default: its module).

    Raises:
        PluginBug: The adapter's ``estimate()`` raised or returned no (tokens, cost) pair.
    """
    plan = DryRun()
    asked = asking(data, options, registry)
    options, tasks = asked.options, asked.tasks
    check_images(asked.folder, asked.scenes, options.input_mode)
    done = completed_epochs(run_dir) if run_dir.exists() else set()
    for ref in asked.scenes:
        scene = ref.load()
        image = None if options.input_mode == "state" else ref.image()
        for epoch, (name, task) in itertools.product(range(1, options.epochs + 1), tasks.items()):
            if (ref.scene_id, name, epoch) in done:
                plan.done[name] = plan.done.get(name, 0) + 1
                continue
            cot = options.cot.get(name, task.default_cot)
            prompt = PromptOptions(options.input_mode, cot, options.force_numeric)
            messages = prompt_messages(task, registry.origin("task", name), scene, image, prompt)
            if isinstance(adapter, Estimating):
                who = origin or object_origin(adapter)
                plan.add(name, *estimated_input(adapter, who, messages))
                continue
            chars = sum(len(p.text) for m in messages for p in m.parts if isinstance(p, TextPart))
            plan.add(name, chars // 4 + (0 if image is None else image_tokens(image)), None)
    return plan


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
