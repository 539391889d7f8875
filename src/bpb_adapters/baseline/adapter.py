"""The baseline adapters: predicted outcomes rendered as JSON text answers.

Each baseline predicts a :class:`~bpb_core.scene.FinalState` for the scene and answers a task with
the part of it that the task asks for, as JSON text, so its answers take the same parse path as a
real model's.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass

from bpb_core.adapters import AdapterOptions, ModelRequest, ModelResponse, Usage
from bpb_core.errors import BadInput, RequestRejected
from bpb_core.scene import WALLS, BallPosition, FinalState, Q1Label, Q2Label, Scene
from bpb_core.truth import answer_for_task

Predictor = Callable[[Scene], FinalState]


def predict_stasis(scene: Scene) -> FinalState:
    """Nothing moves and nothing is hit."""
    return FinalState(
        scene_id=scene.scene_id,
        horizon=scene.horizon,
        q1=[Q1Label(id=b.id, answer="F") for b in scene.balls if b.id != 0],
        q2=[Q2Label(wall=w, answer="F") for w in WALLS],
        predictions=[BallPosition(id=b.id, pos=b.pos) for b in scene.balls],
        simulator="baseline:stasis",
    )


PREDICTORS: dict[str, Predictor] = {"stasis": predict_stasis}


@dataclass
class BaselineAdapter:
    """Answers every request from ``predict(scene)``, offline and instantly."""

    name: str
    predict: Predictor

    async def complete(self, request: ModelRequest) -> ModelResponse:
        started = time.perf_counter()
        if request.scene is None:
            raise RequestRejected(f"{self.name} needs the scene in the request")
        final = self.predict(request.scene)
        text = json.dumps(answer_for_task(request.task, final))
        return ModelResponse(
            text=text,
            usage=Usage(0, 0, 0, 0),
            cost=0.0,  # a local computation really costs nothing
            latency=time.perf_counter() - started,
            model_id=self.name,
            finish_reason="stop",
        )


def make_adapter(model: str, options: AdapterOptions) -> BaselineAdapter:
    """Build ``baseline:<model>``."""
    predictor = PREDICTORS.get(model)
    if predictor is None:
        known = ", ".join(f"baseline:{m}" for m in sorted(PREDICTORS))
        raise BadInput(f"unknown baseline {model!r}; known: {known}")
    return BaselineAdapter(f"baseline:{model}", predictor)
