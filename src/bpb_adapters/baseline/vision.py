"""``baseline:vision``: perception from the image, then the family's own physics.

It reads only what a model is given (the input image and the prompt text) through the scene
family's :class:`~bpb_core.capabilities.Perceiving` capability, runs the dataset's simulator on
the scene it read and answers each task with the part of the result the task's ``expected()``
cuts, as JSON text through the same parse path as a model. Against ``baseline:oracle`` (the same
physics on the true scene) it shows how much of a perfect physicist's score survives reading
the scene from a PNG.

The true scene in the request is used for one thing only: measuring the perception error
(:meth:`~bpb_core.capabilities.Perceiving.perception_error`) and, when the family offers it, the
image's own ceiling (:meth:`~bpb_core.capabilities.BoundsPerception.perception_ceiling`: which
answers survive the image's resolution even for a perfect reader), returned as the reply's
``metadata`` and summarised per horizon by the report. When the image cannot be read the reply
says ``unknown`` and why: it fails to parse, is re-asked and finally scored wrong, and the
reason is kept in the answer's metadata (``perception_failed``).
"""

from __future__ import annotations

import hashlib
import time
from collections import OrderedDict
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar

from bpb_adapters.baseline.adapter import PluginLookup, expected_text
from bpb_core.capabilities import BoundsPerception, Perceiving
from bpb_core.errors import PluginBug, RequestRejected, blamed
from bpb_core.model_calls import ImagePart, ModelRequest, ModelResponse, TextPart
from bpb_core.plugin_calls import perception, simulated_truth

if TYPE_CHECKING:
    from bpb_core.interfaces import SceneFamily
    from bpb_core.registry import Registry

T = TypeVar("T")
CACHE_SIZE = 64  # perceived scenes kept (the tasks of one scene share its image)


def _cached(cache: OrderedDict[str, T], key: str, build: Callable[[], T]) -> T:
    """``cache[key]``, built on first use; the oldest of more than :data:`CACHE_SIZE` go."""
    if key not in cache:
        cache[key] = build()
        if len(cache) > CACHE_SIZE:
            cache.popitem(last=False)
    return cache[key]


def _named_values(origin: str, what: str, values: object) -> dict[str, Any]:
    """``values`` as a dict, if it is a mapping of names (the reply's metadata, where anything
    else would fail far from its cause, blamed on the adapter)."""
    if isinstance(values, Mapping) and all(isinstance(key, str) for key in values):
        return dict(values)
    raise PluginBug(
        f"{origin}: {what} returned {type(values).__name__}; expected a dict of named values"
    )


@dataclass
class VisionAdapter(PluginLookup):
    """Reads the scene from the image, simulates it and answers (see the module docstring)."""

    name: str = "baseline:vision"
    _registry: Registry | None = field(default=None, repr=False)
    _components: dict[str, Any] = field(default_factory=dict, repr=False)
    _seen: OrderedDict[str, tuple[Any, str | None]] = field(default_factory=OrderedDict, repr=False)
    _measured: OrderedDict[str, dict[str, Any]] = field(default_factory=OrderedDict, repr=False)

    def cannot_answer(self, family: SceneFamily) -> str | None:
        """``None`` when ``family`` can read its scenes back from their images."""
        if isinstance(family, Perceiving):
            return None
        return f"the {family.name} scene family cannot read scenes from images"

    def needs_simulator(self) -> bool:
        """It runs the dataset's simulator on the scene it reads."""
        return True

    def _answer(self, request: ModelRequest, family: SceneFamily) -> tuple[str, dict[str, Any]]:
        if not isinstance(family, Perceiving):
            raise RequestRejected(f"{self.name}: {self.cannot_answer(family)}")
        parts = [p for m in request.messages for p in m.parts]
        images = [p.data for p in parts if isinstance(p, ImagePart)]
        if not images:
            missing = "no image in the request (input mode state)"
            return f"unknown: {missing}", {"perception_failed": missing}
        image, prompt = images[0], "\n".join(p.text for p in parts if isinstance(p, TextPart))
        origin = self._plugins().origin("scene_family", str(request.family))
        # one scene's image: the image and the prompt's first line (which names the scene)
        key = hashlib.sha256(image + prompt.split("\n", 1)[0].encode()).hexdigest()
        perceived, reason = _cached(
            self._seen, key, lambda: perception(family, origin, image, prompt)
        )
        if reason is not None:
            return f"unknown: the image could not be read: {reason}", {"perception_failed": reason}
        simulator = self._simulator(request, family, origin)
        truth = simulated_truth(family, origin, perceived, simulator)
        task = self._task(request.task)
        scene = request.scene  # the truth: only to measure

        def measure() -> dict[str, Any]:
            """The perception error and the image's ceiling, once per image (the tasks of a
            scene share them)."""
            name = str(getattr(family, "name", type(family).__name__))
            what = f"scene family {name!r}: perception_error()"
            with blamed(origin, what):
                found = _named_values(origin, what, family.perception_error(perceived, scene))
            if isinstance(family, BoundsPerception):
                what = f"scene family {name!r}: perception_ceiling()"
                with blamed(origin, what):
                    ceiling = family.perception_ceiling(image, prompt, scene, simulator)
                found |= _named_values(origin, what, ceiling)
            return found

        measured: dict[str, Any] = {}
        if scene is not None:
            measured = _cached(self._measured, key, measure)
        return expected_text(self._plugins(), request.task, task, truth), dict(measured)

    async def complete(self, request: ModelRequest) -> ModelResponse:
        """Answer from the image and prompt in ``request``."""
        started = time.perf_counter()
        if request.family is None:
            raise RequestRejected(f"{self.name} needs the scene's family in the request")
        text, metadata = self._answer(request, self._family(str(request.family)))
        return self._reply(text, started, metadata)
