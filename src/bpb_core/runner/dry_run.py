"""What a run would send, without sending it: the calls and tokens of a run (``bpb run
--dry-run``) and the exact messages of one scene and task (``bpb prompt``).

The token estimate is the adapter's own when it can give one (:class:`Estimating`: the
provider's tokenizer and image rule, and the input cost); otherwise prompt characters / 4 plus
an image estimate from the PNG size (OpenAI's tile rule: 85 + 170 per 512-pixel tile after
scaling to fit 2048x768). Output cost is a range: typical (the mean output of the pairs the run
folder already holds, from earlier sessions or ``--pilot``; before any, an assumed
:data:`TYPICAL_OUTPUT` tokens per call) and at the cap (every call using its whole output cap,
as ``--max-cost`` reserves it, from :class:`~bpb_core.capabilities.Bounding`).

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
from bpb_core.dataset.reader import check_image, dataset_family, resolve_data
from bpb_core.errors import BadInput
from bpb_core.interfaces import PromptOptions
from bpb_core.layout import INIT, MANIFEST, iter_scene_keys
from bpb_core.model_calls import CallCeiling, ImagePart, Message, TextPart
from bpb_core.plugin_calls import call_ceiling, estimated_input, prompt_messages
from bpb_core.run_folder import COMPLETE, AnswerRecord, iter_answers
from bpb_core.runner.options import RunOptions
from bpb_core.runner.scenes import asking, check_images
from bpb_core.scored_units import object_origin
from bpb_core.validated_files import read_model

if TYPE_CHECKING:
    from bpb_core.dataset.reader import DataFolder
    from bpb_core.registry import Registry


TYPICAL_OUTPUT = 1000
"""Output tokens per call assumed before any reply of the run is seen (``--pilot`` measures)."""


def plus(total: float | None, more: float | None) -> float | None:
    """``total + more``, unknown (``None``) once either is."""
    return None if total is None or more is None else total + more


@dataclass
class TaskPlan:
    """What a run would send for one task and what it may cost.

    Attributes:
        calls: Calls to send (pairs already complete are not counted).
        done: Pairs already complete.
        input_tokens: Estimated input tokens (first attempts only).
        input_cost: Their cost in USD (``None``: no price known, or no estimate).
        cap_tokens: Output tokens if every call used its whole output cap (``None``: no
            limit known).
        output_price: USD per output token (``None``: no price known).
        seen: Pairs done with replies (earlier sessions or a pilot), whose usage is the basis of
            the typical figures.
        seen_output: Their output tokens, re-asks included.
        seen_cost: Their cost (``None`` when one is unknown).
    """

    calls: int = 0
    done: int = 0
    input_tokens: int = 0
    input_cost: float | None = 0.0
    cap_tokens: int | None = 0
    output_price: float | None = None
    seen: int = 0
    seen_output: int = 0
    seen_cost: float | None = 0.0

    def add(self, tokens: int, cost: float | None, ceiling: CallCeiling | None = None) -> None:
        """Count one call: its input tokens and cost and, from ``ceiling``, its output cap."""
        self.calls += 1
        self.input_tokens += tokens
        self.input_cost = plus(self.input_cost, cost)
        cap = None if ceiling is None else ceiling.output_tokens
        self.cap_tokens = None if self.cap_tokens is None or cap is None else self.cap_tokens + cap
        self.output_price = None if ceiling is None else ceiling.output_price

    def saw(self, record: AnswerRecord) -> None:
        """Count a pair done with replies as a sample of the typical usage."""
        self.done += 1
        if record.attempts and record.usage.output_tokens:
            self.seen += 1
            self.seen_output += record.usage.output_tokens
            self.seen_cost = plus(self.seen_cost, record.cost)

    @property
    def typical_tokens(self) -> float:
        """Output tokens per call: the mean of the pairs seen, else :data:`TYPICAL_OUTPUT`
        (within the cap)."""
        if self.seen:
            return self.seen_output / self.seen
        if not self.calls or self.cap_tokens is None:
            return float(TYPICAL_OUTPUT)
        return float(min(TYPICAL_OUTPUT, self.cap_tokens / self.calls))

    @property
    def typical_output_cost(self) -> float | None:
        """USD of the calls' output at the typical tokens per call."""
        if self.output_price is None:
            return None if self.calls else 0.0
        return self.calls * self.typical_tokens * self.output_price

    @property
    def cap_output_cost(self) -> float | None:
        """USD of the calls' output if each used its whole cap."""
        if self.output_price is None or self.cap_tokens is None:
            return None if self.calls else 0.0
        return self.cap_tokens * self.output_price

    @property
    def projected(self) -> float | None:
        """USD the calls would cost: the mean real cost of the pairs seen (input, output and
        re-asks) times the calls when there are some, else input plus typical output."""
        if self.seen and self.seen_cost is not None:
            return self.calls * self.seen_cost / self.seen
        typical = self.typical_output_cost
        return None if self.input_cost is None or typical is None else self.input_cost + typical


@dataclass
class DryRun:
    """What a run of one adapter would send and cost, per task.

    Attributes:
        tasks: Per task, its :class:`TaskPlan`.
        basis: Where the adapter's figures come from (its tokenizer, prices and output cap),
            empty when it cannot bound a call.
    """

    tasks: dict[str, TaskPlan] = field(default_factory=dict)
    basis: str = ""

    def task(self, name: str) -> TaskPlan:
        """The plan of ``name`` (empty until counted)."""
        return self.tasks.setdefault(name, TaskPlan())


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
    """Count the calls and estimate the input tokens (and, when ``adapter`` can estimate and
    bound a call, the input cost and the output cost, typical and at the cap) of a run without
    sending anything; pairs already done in ``run_dir`` give the typical usage. ``origin`` is
    who supplied ``adapter`` (default: its module).

    Raises:
        PluginBug: The adapter's ``estimate()`` or ``ceiling()`` raised or returned no
            (tokens, cost) pair or ceiling.
    """
    plan = DryRun()
    asked = asking(data, options, registry)
    options, tasks = asked.options, asked.tasks
    check_images(asked.folder, asked.scenes, options.input_mode)
    done = _seen(run_dir, plan, {r.scene_id for r in asked.scenes}, options.epochs)
    who = origin or object_origin(adapter)
    for ref in asked.scenes:
        scene = ref.load()
        image = None if options.input_mode == "state" else ref.image()
        for epoch, (name, task) in itertools.product(range(1, options.epochs + 1), tasks.items()):
            if (ref.scene_id, name, epoch) in done:
                continue
            cot = options.cot.get(name, task.default_cot)
            prompt = PromptOptions(options.input_mode, cot, options.force_numeric)
            messages = prompt_messages(task, registry.origin("task", name), scene, image, prompt)
            ceiling = call_ceiling(adapter, who, messages, options.max_tokens)
            if ceiling is not None:  # its input figures are the estimate's
                plan.basis = ceiling.basis
                plan.task(name).add(ceiling.input_tokens, ceiling.input_cost, ceiling)
            elif isinstance(adapter, Estimating):
                plan.task(name).add(*estimated_input(adapter, who, messages))
            else:
                plan.task(name).add(_rough_tokens(messages, image), None)
    return plan


def _rough_tokens(messages: tuple[Message, ...], image: bytes | None) -> int:
    """Prompt characters / 4 plus the image's tokens by OpenAI's tile rule."""
    chars = sum(len(p.text) for m in messages for p in m.parts if isinstance(p, TextPart))
    return chars // 4 + (0 if image is None else image_tokens(image))


def _seen(run_dir: Path, plan: DryRun, scenes: set[str], epochs: int) -> set[tuple[str, str, int]]:
    """The pairs of the selection already done in ``run_dir``, counted in ``plan``."""
    done = set()
    for _, record in iter_answers(run_dir) if run_dir.exists() else ():
        if record.status in COMPLETE and record.scene_id in scenes and record.epoch <= epochs:
            done.add((record.scene_id, record.task, record.epoch))
            plan.task(record.task).saw(record)
    return done


def _scene_file(scene: Path, data: Path | None) -> Path:
    """``init.json`` of ``scene``: a file, a scene folder, or a scene id in ``data``."""
    if data is not None and not scene.exists():
        if not data.is_dir():
            raise BadInput(f"{data}: --data: no such dataset folder")
        data = resolve_data(data)  # a Hugging Face export opens as the folder it came from
        found = [k.dir(data) / INIT for k in iter_scene_keys(data) if k.scene_id == str(scene)]
        found = [path for path in found if path.is_file()]
        if not found:
            raise BadInput(f"{data}: --data: no scene with id {str(scene)!r} (like h1_0000)")
        return found[0]
    if scene.is_dir():
        scene = scene / INIT
    if not scene.is_file():
        raise BadInput(f"{scene}: no such scene file (give init.json, its folder, or an id)")
    return scene


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
