"""What a run would send, without sending it (``bpb run --dry-run``).

The token estimate is the adapter's own when it can give one (:class:`Estimating`: the
provider's tokenizer and image rule, and the input cost); otherwise prompt characters / 4 plus
an image estimate from the PNG size (OpenAI's tile rule: 85 + 170 per 512-pixel tile after
scaling to fit 2048x768). It is a planning figure, not a bill: output tokens are not included.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from bpb_core.capabilities import Estimating
from bpb_core.interfaces import PromptOptions
from bpb_core.model_calls import TextPart
from bpb_core.plugin_calls import estimated_input, prompt_messages
from bpb_core.run_folder import completed_epochs
from bpb_core.runner.asking import asking
from bpb_core.runner.options import RunOptions
from bpb_core.runner.scenes import check_images
from bpb_core.scored_units import object_origin

if TYPE_CHECKING:
    from bpb_core.dataset.reader import DataFolder
    from bpb_core.interfaces import Task
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


def _samples(tasks: dict[str, Task], epochs: int) -> list[tuple[str, Task, int]]:
    return [(name, task, e) for e in range(1, epochs + 1) for name, task in tasks.items()]


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
        for name, task, epoch in _samples(tasks, options.epochs):
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
