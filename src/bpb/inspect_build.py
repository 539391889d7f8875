"""Build an Inspect AI :class:`~inspect_ai.Task` from bpb tasks and a bpb dataset.

One sample per scene and task: the input is exactly the messages ``bpb run`` sends
(:func:`bpb_core.build_messages`: the scene's input image and the task's prompt), the target is
the correct answer's JSON, and the scorer is bpb's own: the task's parser and scorer as an Inspect
scorer, with per-task and suite metrics that equal what ``bpb report`` computes from a run folder.
Generation uses the paper's protocol: temperature 0.

A sample's :class:`~inspect_ai.scorer.Score` is the scene's score under the task's rule (the
share of right units, or all-or-nothing), its ``answer`` the parsed answer JSON and its
``metadata`` every unit (each ball, each wall: truth, prediction, right or wrong, distance).
"""

from __future__ import annotations

import base64
import dataclasses
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from inspect_ai import Task
from inspect_ai.dataset import MemoryDataset, Sample
from inspect_ai.model import (
    ChatMessage,
    ChatMessageAssistant,
    ChatMessageSystem,
    ChatMessageUser,
    Content,
    ContentImage,
    ContentText,
    GenerateConfig,
)
from inspect_ai.scorer import (
    Metric,
    SampleScore,
    Score,
    Scorer,
    Target,
    Value,
    mean,
    metric,
    scorer,
    stderr,
)
from inspect_ai.solver import TaskState, generate

from bpb_core import ImagePart, build_messages, load_dataset, make_registry, score_answer
from bpb_core.errors import BadInput

if TYPE_CHECKING:
    from bpb_core import Dataset, DatasetScene, Registry
    from bpb_core.interfaces import InputMode

_ROLES = {"system": ChatMessageSystem, "user": ChatMessageUser, "assistant": ChatMessageAssistant}


def bpb_task(
    tasks: Sequence[str] | None = None,
    data: str | Path = "data",
    *,
    suite: str | None = None,
    input_mode: InputMode = "image",
    horizons: Sequence[float] | str | float | None = None,
    limit: int | None = None,
    cot: bool | None = None,
    registry: Registry | None = None,
) -> Task:
    """An Inspect task asking ``tasks`` (or a suite's tasks) about every selected scene.

    Args:
        tasks: bpb task names (``q1``, or any installed plugin's task).
        data: A dataset folder or a Hugging Face export of one.
        suite: A bpb suite (``total``): its tasks, and its weighted total as a metric.
        input_mode: ``image`` (default), ``image+state`` or ``state``.
        horizons: Horizons to ask about (a list, a number or ``"1,3"``; default: all).
        limit: Scenes per horizon at most.
        cot: Ask for reasoning first (default: each task's own default, as ``bpb run``).
        registry: Where tasks, scorers and suites come from (default: every installed plugin).

    Raises:
        BadInput: No tasks and no suite, an unknown suite, or a bad dataset (names the file).
    """
    registry = registry or make_registry()
    weights: dict[str, float] = {}
    if suite is not None:
        found = [dict(info.weights) for info in registry.suites() if info.name == suite]
        if not found:
            known = ", ".join(info.name for info in registry.suites()) or "none"
            raise BadInput(f"suite: no suite {suite!r} (installed: {known})")
        weights = found[0]
    names = list(tasks or weights)
    if not names:
        raise BadInput("bpb_task: give tasks or a suite")
    if isinstance(horizons, str):  # Inspect's -T horizons=1,3
        horizons = [float(h) for h in horizons.split(",") if h.strip()]
    elif isinstance(horizons, int | float):  # -T horizons=3
        horizons = [horizons]
    chosen = None if horizons is None else [float(h) for h in horizons]
    dataset = load_dataset(data, chosen, limit, registry=registry)
    samples = [
        _sample(name, scene, input_mode, cot, registry) for scene in dataset for name in names
    ]
    return Task(
        dataset=MemoryDataset(samples, name=f"bpb:{dataset.root.name}"),
        solver=generate(),
        scorer=bpb_scorer(dataset, names, weights, cot=cot, registry=registry),
        metrics=[bpb_scores(names, weights), *([] if weights else [mean(), stderr()])],
        config=GenerateConfig(temperature=0.0),
        metadata={  # what bpb report needs to read the log as a run (bpb_core.results)
            "bpb_task_names": names,
            "bpb_dataset": str(dataset.root.resolve()),
            "bpb_dataset_hash": dataset.dataset_hash,
            "bpb_horizons": chosen,
            "bpb_limit": limit,
            "bpb_input_mode": input_mode,
        },
    )


def _sample(
    task: str, scene: DatasetScene, mode: InputMode, cot: bool | None, registry: Registry
) -> Sample:
    chat: list[ChatMessage] = []  # bpb's messages as Inspect's, images as data URIs
    for message in build_messages(task, scene, mode, cot=cot, registry=registry):
        content: list[Content] = []
        for part in message.parts:
            if isinstance(part, ImagePart):
                encoded = base64.b64encode(part.data).decode("ascii")
                content.append(ContentImage(image=f"data:{part.media_type};base64,{encoded}"))
            else:
                content.append(ContentText(text=part.text))
        chat.append(_ROLES[message.role](content=content))
    found = registry.task(task)
    expected = found.expected(scene.truth)
    return Sample(
        id=f"{scene.scene_id}/{task}",
        input=chat,
        target=json.dumps(expected),
        metadata={
            "scene_id": scene.scene_id,
            "task": task,
            "horizon": scene.horizon,
            "index": scene.key.index,
            "stable": scene.stable,
            "input_mode": mode,
            "cot": found.default_cot if cot is None else cot,
        },
    )


@metric
def bpb_scores(tasks: Sequence[str], weights: Mapping[str, float]) -> Metric:
    """Each task's mean scene score (what ``bpb report`` shows per task), and the suite's
    weighted total when ``weights`` are given (the paper's ``total``)."""

    def compute(scores: list[SampleScore]) -> Value:
        by_task: dict[str, list[float]] = {name: [] for name in tasks}
        for sample in scores:
            name = str((sample.score.metadata or {}).get("task"))
            by_task.setdefault(name, []).append(sample.score.as_float())
        means = {name: sum(v) / len(v) if v else 0.0 for name, v in by_task.items()}
        if weights:
            means["total"] = sum(w * means.get(name, 0.0) for name, w in weights.items())
        return means

    return compute


@scorer(metrics=[])
def bpb_scorer(
    dataset: Dataset,
    tasks: Sequence[str],
    weights: Mapping[str, float],
    *,
    cot: bool | None = None,
    registry: Registry | None = None,
) -> Scorer:
    """Score a sample's completion with its bpb task's parser and scorer."""

    async def score(state: TaskState, target: Target) -> Score:
        name = str(state.metadata["task"])
        scene = dataset[str(state.metadata["scene_id"])]
        result = score_answer(name, scene, state.output.completion, cot=cot, registry=registry)
        return Score(
            value=result.score,
            answer=None if result.answer is None else json.dumps(result.answer),
            explanation=result.error,
            metadata={
                "task": name,
                "scene_id": result.scene_id,
                "status": result.status,
                "rule": result.rule,
                "units": [dataclasses.asdict(unit) for unit in result.units],
            },
        )

    return score
