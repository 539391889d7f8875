"""bpb's scoring inside Inspect AI: the task's parser and scorer as an Inspect scorer, and
per-task and suite metrics that equal what ``bpb report`` computes from a run folder.

A sample's :class:`~inspect_ai.scorer.Score` is the scene's score under the task's rule (the
share of right units, or all-or-nothing), its ``answer`` the parsed answer JSON and its
``metadata`` every unit (each ball, each wall: truth, prediction, right or wrong, distance).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from inspect_ai.scorer import (
    Metric,
    SampleScore,
    Score,
    Scorer,
    Target,
    Value,
    metric,
    scorer,
)
from inspect_ai.solver import TaskState

from bpb_core import score_answer

if TYPE_CHECKING:
    from bpb_core import Dataset, Registry


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
