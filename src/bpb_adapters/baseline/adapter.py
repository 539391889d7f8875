"""The baseline adapters: reference predictions rendered as JSON text answers.

``baseline:oracle`` answers from the scene family's own ground truth (the dataset's simulator run
on the scene: the ceiling, and an end-to-end check); any other model names a prediction the
scene's family offers (:class:`~bpb_core.capabilities.Predicting`; ``stasis``, ``straight`` and
``random`` for billiards). Either way the adapter answers a task with the part
the task's ``expected()`` cuts from the prediction, as JSON text, so its answers take the same
parse path as a real model's. Nothing here knows a particular family or task.
"""

from __future__ import annotations

import json
import random
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

from bpb_core.capabilities import Perceiving, Predicting
from bpb_core.errors import BadInput, ParseFailure, PluginBug, RequestRejected, UnknownName, blamed
from bpb_core.interfaces import PromptOptions
from bpb_core.model_calls import AdapterOptions, ModelRequest, ModelResponse, Usage
from bpb_core.plugin_calls import (
    loaded_config,
    offered_predictors,
    prediction,
    simulated_truth,
    simulator_named,
)
from bpb_core.scored_units import object_origin
from bpb_core.simulator_spec import parse_spec

if TYPE_CHECKING:
    from bpb_adapters.baseline.vision import VisionAdapter
    from bpb_core.interfaces import SceneFamily, Simulator, Task
    from bpb_core.registry import Registry

ORACLE = "oracle"
VISION = "vision"


def expected_text(
    registry: Registry, name: str, task: Task, truth: Any, scene: Any = None, *, check: bool = False
) -> str:
    """The task's ``expected(truth)`` as JSON text, blaming the task's plugin, not the adapter,
    for a bug: an ``expected()`` that raises, returns what JSON cannot hold, or (with ``check``,
    the oracle: the truth must be a valid answer) returns what the task's own parser refuses.

    Raises:
        PluginBug: One line naming the task's plugin.
    """
    origin = registry.origin("task", name)
    what = f"task {name!r}: expected()"
    with blamed(origin, what):
        value = task.expected(truth)
    try:
        text = json.dumps(value)
    except (TypeError, ValueError) as exc:
        raise PluginBug(f"{origin}: {what} returned what JSON cannot hold: {exc}") from None
    if check:
        try:
            with blamed(origin, f"task {name!r}: parse()"):
                task.parse(text, scene, PromptOptions())
        except ParseFailure as failure:
            shown = text if len(text) <= 80 else f"{text[:77]}..."
            raise PluginBug(
                f"{origin}: {what} returned {shown}, which the task's own parser refuses: {failure}"
            ) from None
    return text


def _registry() -> Registry:
    from bpb_core.registry import make_registry

    return make_registry(warn=False)  # the CLI has shown its warnings already


class PluginLookup:
    """Tasks, families and simulators looked up by name, in the registry that built the
    adapter (:class:`bpb_core.capabilities.UsesRegistry`) or else the installed plugins, and
    kept once built; and the offline reply. A dataclass using it declares ``name``,
    ``_registry`` and ``_components``."""

    name: str
    _registry: Registry | None
    _components: dict[str, Any]

    def use_registry(self, registry: Registry) -> None:
        """Look tasks and families up in ``registry`` (the one that built this adapter)."""
        self._registry = registry
        self._components.clear()

    def _plugins(self) -> Registry:
        if self._registry is None:
            self._registry = _registry()
        return self._registry

    def _component(self, key: str, build: Any) -> Any:
        if key not in self._components:
            self._components[key] = build(self._plugins())
        return self._components[key]

    def _family(self, name: str) -> SceneFamily:
        return cast("SceneFamily", self._component(f"f:{name}", lambda r: r.scene_family(name)))

    def _task(self, name: str) -> Task:
        return cast("Task", self._component(f"t:{name}", lambda r: r.task(name)))

    def _reply(
        self, text: str, started: float, metadata: dict[str, Any] | None = None
    ) -> ModelResponse:
        """The answer ``text``, computed locally since ``started`` (it really costs nothing)."""
        return ModelResponse(
            text=text,
            usage=Usage(0, 0, 0, 0),
            cost=0.0,
            latency=time.perf_counter() - started,
            model_id=self.name,
            finish_reason="stop",
            metadata=metadata or {},
        )

    def _simulator(self, request: ModelRequest, family: SceneFamily, origin: str) -> Simulator:
        """The simulator the request names, else the one the family's default config names
        (asked checked, blaming ``origin``: who supplied the family), built with the options
        its spec gives (``pymunk:dt=0.0005``), as generation built it."""
        name = request.simulator or simulator_named(
            family, origin, loaded_config(family, origin, None)
        )

        def build(registry: Registry) -> Simulator:
            named = parse_spec(name, "dataset.json: config: simulator")
            return registry.simulator(named.name, named.options)

        return cast("Simulator", self._component(f"s:{name}", build))


@dataclass
class BaselineAdapter(PluginLookup):
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
    _components: dict[str, Any] = field(default_factory=dict, repr=False)

    def cannot_answer(self, family: SceneFamily) -> str | None:
        """``None`` when ``family`` offers this prediction (every family has the oracle), else
        what it offers."""
        offered: tuple[str, ...] = (ORACLE,)
        if isinstance(family, Predicting):
            try:  # who supplied the family: its registry entry, else its module
                origin = self._plugins().origin("scene_family", family.name)
            except UnknownName:
                origin = object_origin(family)
            offered += offered_predictors(family, origin)
        offered += (VISION,) if isinstance(family, Perceiving) else ()
        if self.model in offered:
            return None
        known = ", ".join(f"baseline:{name}" for name in offered)
        return f"the {family.name} scene family offers no such prediction; known: {known}"

    def needs_simulator(self) -> bool:
        """Only the oracle runs the dataset's simulator; the predictions do not."""
        return self.model == ORACLE

    async def complete(self, request: ModelRequest) -> ModelResponse:
        """Answer from the scene in ``request`` (baselines never read the prompt)."""
        started = time.perf_counter()
        if request.scene is None or request.family is None:
            raise RequestRejected(f"{self.name} needs the scene and its family in the request")
        name = str(request.family)
        family = self._family(name)
        origin = self._plugins().origin("scene_family", name)
        if self.model == ORACLE:
            simulator = self._simulator(request, family, origin)
            truth = simulated_truth(family, origin, request.scene, simulator)
        else:
            why = self.cannot_answer(family)
            if why is not None:
                raise RequestRejected(f"{self.name}: {why}")
            assert isinstance(family, Predicting)
            rng = random.Random(f"{self.seed}:{request.scene.scene_id}:{request.task}")
            truth = prediction(family, origin, self.model, request.scene, rng)
        task = self._task(request.task)
        oracle = self.model == ORACLE  # the truth must be a valid answer
        return self._reply(
            expected_text(self._plugins(), request.task, task, truth, request.scene, check=oracle),
            started,
        )


def make_adapter(model: str, options: AdapterOptions) -> BaselineAdapter | VisionAdapter:
    """Build ``baseline:<model>``: ``oracle``, ``vision`` (perception from the image, then the
    dataset's simulator) or a prediction the scene family offers (checked against the dataset's
    family before a run starts)."""
    if not model.strip():
        raise BadInput("--adapter baseline:: give a model, e.g. baseline:oracle")
    if model == VISION:
        from bpb_adapters.baseline.vision import VisionAdapter

        return VisionAdapter()
    return BaselineAdapter(f"baseline:{model}", model, options.seed)
