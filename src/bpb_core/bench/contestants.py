"""Contestants of ``bpb bench sim``: simulator specs, the family that compares them, timing.

A contestant is ``name`` or ``name:key=value,...`` (``mysim``, ``mysim:dt=0.01,order=2``):
a registered simulator and the options it is built with, as ``bpb simulate`` takes them.
"""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING, Any

from bpb_core.capabilities import Comparing
from bpb_core.errors import BadInput
from bpb_core.simulator_spec import SimulatorSpec, parse_spec

if TYPE_CHECKING:
    from bpb_core.interfaces import Simulator
    from bpb_core.registry import Registry


Contestant = SimulatorSpec
"""A simulator name and its options, parsed from ``name:key=value,...``."""


def parse_contestant(spec: str, flag: str = "--contestant") -> Contestant:
    """Parse ``name`` or ``name:key=value,...`` (:func:`~bpb_core.simulator_spec.parse_spec`);
    ``flag`` names where the spec was given (``--contestant``, ``--reference``, ``--scaling``...).

    Raises:
        BadInput: An option is not ``key=value``.
    """
    return parse_spec(spec, flag)


def comparing_family(registry: Registry, name: str) -> Comparing:
    """The scene family ``name``, which must be able to compare simulators.

    Raises:
        BadInput: It is not installed or has no :class:`Comparing` capability.
    """
    family = registry.scene_family(name)
    if not isinstance(family, Comparing):
        raise BadInput(f"--family: the {name} scene family cannot compare simulators")
    return family


def build_simulators(
    registry: Registry, family: str, entries: list[Contestant], flag: str = "--contestant"
) -> dict[str, Simulator]:
    """The simulators of ``entries`` by spec, in order (``flag`` as in :func:`parse_contestant`).

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
