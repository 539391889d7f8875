"""The baseline adapters: predicted outcomes rendered as JSON text answers.

Each baseline predicts a :class:`~bpb_core.scene.FinalState` for the scene and answers a task with
the part the task's ``expected()`` cuts from it, as JSON text, so its answers take the same parse
path as a real model's.
"""

from __future__ import annotations

import json
import random
import time
from dataclasses import dataclass, field
from typing import Any

from bpb_adapters.baseline.predictors import PREDICTORS, Predictor
from bpb_core.adapters import AdapterOptions, ModelRequest, ModelResponse, Usage
from bpb_core.errors import BadInput, RequestRejected


def _task(name: str) -> Any:
    from bpb_core.registry import make_registry

    return make_registry().task(name)


@dataclass
class BaselineAdapter:
    """Answers every request from ``predict(scene, rng)``, offline and instantly.

    Attributes:
        name: ``baseline:<model>``.
        predict: The predictor.
        seed: Seed of the per-(scene, task) generator (``baseline:random``).
    """

    name: str
    predict: Predictor
    seed: int = 0
    _tasks: dict[str, Any] = field(default_factory=dict, repr=False)

    def _expected(self, task: str) -> Any:
        if task not in self._tasks:
            self._tasks[task] = _task(task)
        return self._tasks[task]

    async def complete(self, request: ModelRequest) -> ModelResponse:
        """Answer from the scene in ``request`` (baselines never read the prompt)."""
        started = time.perf_counter()
        if request.scene is None:
            raise RequestRejected(f"{self.name} needs the scene in the request")
        rng = random.Random(f"{self.seed}:{request.scene.scene_id}:{request.task}")
        final = self.predict(request.scene, rng)
        text = json.dumps(self._expected(request.task).expected(final))
        return ModelResponse(
            text=text,
            usage=Usage(0, 0, 0, 0),
            cost=0.0,  # a local computation really costs nothing
            latency=time.perf_counter() - started,
            model_id=self.name,
            finish_reason="stop",
        )


def make_adapter(model: str, options: AdapterOptions) -> BaselineAdapter:
    """Build ``baseline:<model>`` (stasis, straight, random or oracle)."""
    factory = PREDICTORS.get(model)
    if factory is None:
        known = ", ".join(f"baseline:{m}" for m in sorted(PREDICTORS))
        raise BadInput(f"--adapter baseline:{model}: unknown baseline; known: {known}")
    return BaselineAdapter(f"baseline:{model}", factory(), options.seed)
