"""The baseline adapters: reference predictions rendered as JSON text answers.

``baseline:oracle`` answers from the scene family's own ground truth (its default simulator run
on the scene: the ceiling, and an end-to-end check); the other models (``stasis``, ``straight``,
``random`` for billiards) are predictions the family offers
(:class:`~bpb_core.interfaces.Predicting`). Either way the adapter answers a task with the part
the task's ``expected()`` cuts from the prediction, as JSON text, so its answers take the same
parse path as a real model's. Nothing here knows a particular family or task.
"""

from __future__ import annotations

import json
import random
import time
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from bpb_core.errors import BadInput, RequestRejected
from bpb_core.interfaces import Predicting
from bpb_core.model_calls import AdapterOptions, ModelRequest, ModelResponse, Usage

if TYPE_CHECKING:
    from bpb_core.interfaces import SceneFamily, Simulator, Task
    from bpb_core.registry import Registry

MODELS = ("stasis", "straight", "random", "oracle")
ORACLE = "oracle"


def _registry() -> Registry:
    from bpb_core.registry import PluginWarning, make_registry

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PluginWarning)  # the CLI has shown them already
        return make_registry()


@dataclass
class BaselineAdapter:
    """Answers every request from a prediction of the request's scene, offline and instantly.

    Attributes:
        name: ``baseline:<model>``.
        model: Which prediction (``oracle`` or one the scene's family offers).
        seed: Seed of the per-(scene, task) generator (``baseline:random``).
    """

    name: str
    model: str
    seed: int = 0
    _registry: Registry | None = field(default=None, repr=False)
    _cache: dict[str, Any] = field(default_factory=dict, repr=False)

    def _component(self, key: str, build: Any) -> Any:
        if key not in self._cache:
            if self._registry is None:
                self._registry = _registry()
            self._cache[key] = build(self._registry)
        return self._cache[key]

    def _predict(self, family_name: str, scene: Any, rng: random.Random) -> Any:
        family: SceneFamily = self._component(
            f"f:{family_name}", lambda r: r.scene_family(family_name)
        )
        if self.model == ORACLE:
            simulator: Simulator = self._component(
                f"s:{family_name}",
                lambda r: r.simulator(family.simulator_name(family.load_config(None))),
            )
            return family.ground_truth(scene, simulator, stability=False)
        if not isinstance(family, Predicting) or self.model not in family.predictors:
            offered = [ORACLE, *(family.predictors if isinstance(family, Predicting) else ())]
            raise RequestRejected(
                f"{self.name}: the {family_name} family offers no such prediction "
                f"(it offers: {', '.join(offered)})"
            )
        return family.predict(self.model, scene, rng)

    async def complete(self, request: ModelRequest) -> ModelResponse:
        """Answer from the scene in ``request`` (baselines never read the prompt)."""
        started = time.perf_counter()
        if request.scene is None or request.family is None:
            raise RequestRejected(f"{self.name} needs the scene and its family in the request")
        rng = random.Random(f"{self.seed}:{request.scene.scene_id}:{request.task}")
        truth = self._predict(request.family, request.scene, rng)
        task: Task = self._component(f"t:{request.task}", lambda r: r.task(request.task))
        return ModelResponse(
            text=json.dumps(task.expected(truth)),
            usage=Usage(0, 0, 0, 0),
            cost=0.0,  # a local computation really costs nothing
            latency=time.perf_counter() - started,
            model_id=self.name,
            finish_reason="stop",
        )


def make_adapter(model: str, options: AdapterOptions) -> BaselineAdapter:
    """Build ``baseline:<model>`` (stasis, straight, random or oracle)."""
    if model not in MODELS:
        known = ", ".join(f"baseline:{m}" for m in MODELS)
        raise BadInput(f"--adapter baseline:{model}: unknown baseline; known: {known}")
    return BaselineAdapter(f"baseline:{model}", model, options.seed)
