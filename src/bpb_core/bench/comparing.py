"""The scene family and the simulators of ``bpb bench sim``, its hooks called checked.

Contestants are given as ``name`` or ``name:key=value,...`` (``mysim``, ``mysim:dt=0.01``):
a registered simulator and the options it is built with, as ``bpb simulate`` takes them
(:func:`~bpb_core.simulator_spec.parse_spec`).

:class:`BenchFamily` runs each hook of a :class:`~bpb_core.capabilities.Comparing` (and
:class:`~bpb_core.capabilities.CountsEvents`) family under :func:`~bpb_core.errors.blamed` and
checks what it gives, so a family's mistake is one line naming its plugin
(:class:`~bpb_core.errors.PluginBug`, exit 3) instead of a traceback, a wrong figure, or a
failure counted against the simulator whose outcome the family was looking at.
"""

from __future__ import annotations

import math
import numbers
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from bpb_core.capabilities import Comparing, CountsEvents
from bpb_core.errors import BadInput, PluginBug, blamed
from bpb_core.plugin_calls import family_label, family_model

if TYPE_CHECKING:
    from bpb_core.interfaces import Simulator
    from bpb_core.registry import Registry
    from bpb_core.simulator_spec import SimulatorSpec

ERROR = "error"
"""The key of :meth:`Comparing.compare`'s result that holds the distance to the reference."""


@dataclass(frozen=True)
class BenchFamily:
    """A comparing scene family and who supplied it (``origin``, for one-line errors)."""

    family: Comparing
    origin: str

    @property
    def counts_events(self) -> bool:
        """Whether the family counts events (``--scaling``, µs per event)."""
        return isinstance(self.family, CountsEvents)

    def text(self, attribute: str) -> str:
        """The family's ``bench_reference``, ``bench_description`` or ``bench_measures``,
        checked: a str.

        Raises:
            PluginBug: Reading it raised, or it is no str.
        """
        value = self._attribute(attribute)
        if isinstance(value, str):
            return value
        raise self._bug(f"{attribute} is {type(value).__name__}; expected a str")

    def contestants(self) -> tuple[str, ...]:
        """The family's ``bench_contestants``, checked: specs (a str alone would be read
        letter by letter, each letter refused as an unknown simulator).

        Raises:
            PluginBug: Reading it raised, or it is no tuple or list of str.
        """
        value = self._attribute("bench_contestants")
        if isinstance(value, tuple | list) and all(isinstance(v, str) for v in value):
            return tuple(value)
        raise self._bug(
            f"bench_contestants is {type(value).__name__}; expected a tuple of simulator specs "
            "(str)"
        )

    def scenes(self, count: int, seed: int) -> list[Any]:
        """``bench_scenes(count, seed)``, checked: ``count`` scenes (of the family's
        ``scene_model`` when it has one).

        Raises:
            PluginBug: The family raised or returned something else.
        """
        what = f"bench_scenes({count}, {seed})"
        with blamed(self.origin, f"{self._label()}: {what}"):
            scenes = self.family.bench_scenes(count, seed)
        kind = family_model(self.family, "scene_model") or object
        if not isinstance(scenes, list | tuple):
            raise self._bug(f"{what} returned {type(scenes).__name__}; expected a list of scenes")
        stray = next((s for s in scenes if not isinstance(s, kind)), None)
        if stray is not None:
            raise self._bug(
                f"{what} returned a scene of type {type(stray).__name__}; expected "
                f"{kind.__name__} (the family's scene_model)"
            )
        if len(scenes) != count:
            raise self._bug(f"{what} returned {len(scenes)} scenes; expected {count}")
        return list(scenes)

    def compare(self, outcome: Any, reference: Any, scene: Any) -> dict[str, float]:
        """``compare(outcome, reference, scene)``, checked: named numbers holding ``error``.

        Raises:
            PluginBug: The family raised or returned something else.
        """
        with blamed(self.origin, f"{self._label()}: compare()"):
            measures = self.family.compare(outcome, reference, scene)
        expected = f"expected a dict of named numbers holding {ERROR!r}"
        if not isinstance(measures, dict):
            raise self._bug(f"compare() returned {type(measures).__name__}; {expected}")
        for key, value in measures.items():
            if not (isinstance(key, str) and _number(value)):
                got = f"{key!r}: {type(value).__name__}"
                raise self._bug(f"compare() returned {{{got}, ...}}; {expected}")
        if ERROR not in measures:
            raise self._bug(f"compare() returned no {ERROR!r}; {expected}")
        return {key: float(value) for key, value in measures.items()}

    def events(self, outcome: Any) -> int:
        """``events(outcome)`` (0 when the family does not count events), checked: a count.

        Raises:
            PluginBug: The family raised or returned something else.
        """
        if not isinstance(self.family, CountsEvents):
            return 0
        with blamed(self.origin, f"{self._label()}: events()"):
            count = self.family.events(outcome)
        if isinstance(count, int) and not isinstance(count, bool) and count >= 0:
            return count
        got = repr(count) if isinstance(count, int) else type(count).__name__
        raise self._bug(f"events() returned {got}; expected a count (an int at least 0)")

    def scaled(self, scene: Any, factor: float) -> Any:
        """``scaled_scene(scene, factor)``, checked: a scene of the same type.

        Raises:
            PluginBug: The family raised or returned something else.
        """
        assert isinstance(self.family, CountsEvents), "checked before --scaling runs"
        with blamed(self.origin, f"{self._label()}: scaled_scene()"):
            busy = self.family.scaled_scene(scene, factor)
        if isinstance(busy, type(scene)):
            return busy
        raise self._bug(
            f"scaled_scene() returned {type(busy).__name__}; expected a scene like the one it "
            f"was given ({type(scene).__name__})"
        )

    def _attribute(self, attribute: str) -> Any:
        with blamed(self.origin, f"{self._label()}: reading {attribute}"):
            return getattr(self.family, attribute)

    def _label(self) -> str:
        return family_label(self.family)

    def _bug(self, said: str) -> PluginBug:
        return PluginBug(f"{self.origin}: {self._label()}: {said}")


def bench_family(registry: Registry, name: str) -> BenchFamily:
    """The scene family ``name``, which must be able to compare simulators, its hooks to be
    called checked.

    Raises:
        BadInput: It is not installed or has no :class:`Comparing` capability.
    """
    family = registry.scene_family(name)
    if not isinstance(family, Comparing):
        raise BadInput(f"--family: the {name} scene family cannot compare simulators")
    return BenchFamily(family, registry.origin("scene_family", name))


def _number(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)  # numpy's too


def build_simulators(
    registry: Registry, family: str, entries: list[SimulatorSpec], flag: str = "--contestant"
) -> dict[str, Simulator]:
    """The simulators of ``entries`` by spec, in order (``flag``: where they were given).

    Raises:
        BadInput: A simulator is unknown, simulates another family's scenes, or does not take
            an option or refuses its value (``--contestant 'pymunk:dt=-1': dt: ...``).
    """
    sims: dict[str, Simulator] = {}
    for entry in entries:
        simulates = registry.simulator_info(entry.name).family
        if simulates and simulates != family:
            raise BadInput(f"{flag} {entry.spec}: simulates {simulates} scenes, not {family} ones")
        try:
            sims[entry.spec] = registry.simulator(entry.name, entry.options)
        except BadInput as exc:  # "dt: must be ...": which of the specs given, and where
            raise BadInput(f"{flag} {entry.spec!r}: {exc}") from None
    return sims


def timed_run(sim: Simulator, scene: Any, budget: float = 0.005) -> tuple[Any, float]:
    """Run ``sim`` on ``scene``; fast runs are repeated (up to 5 times, within ``budget``
    seconds) and the quickest counts, so a preempted sub-millisecond run does not dominate."""
    best, spent, runs = math.inf, 0.0, 0
    while runs < 5 and (runs == 0 or spent < budget):
        started = time.perf_counter()
        outcome = sim.run(scene)
        seconds = time.perf_counter() - started
        best, spent, runs = min(best, seconds), spent + seconds, runs + 1
    return outcome, best
