"""Cost against events per scene for ``bpb bench sim --scaling``.

A family that counts events (:class:`~bpb_core.capabilities.CountsEvents`) makes its benchmark
scenes busier by a factor (for instance every velocity times the factor, so more events happen
in the same simulated time). Each chosen simulator runs every scaled scene (the
factors interleaved per scene, so machine noise hits them alike); per factor the result holds the
mean milliseconds and events per scene. If the cost follows the events, the microseconds per
event stay about flat while the events per scene grow. A run that raises (a fixed-step simulator
may refuse a scene made too fast for its step) is a failed scene of that simulator at that
factor, left out of its means, as in the main comparison. As there, each simulator runs once
untimed first, so that loading its imports and compiled code is not timed as the first scene.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from bpb_core.bench.comparing import bench_family
from bpb_core.bench.contestants import build_simulators, comparing_family, parse_contestant
from bpb_core.bench.sim import ScaleRow, SimBench, _Tally, warm_up
from bpb_core.capabilities import CountsEvents
from bpb_core.errors import BadInput

if TYPE_CHECKING:
    from bpb_core.interfaces import Simulator
    from bpb_core.registry import Registry

DEFAULT_FACTORS = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0)


def with_scaling(
    result: SimBench,
    contestants: Sequence[str],
    scenes: int,
    factors: Sequence[float] = DEFAULT_FACTORS,
    registry: Registry | None = None,
) -> SimBench:
    """``result`` with scaling rows for ``contestants`` on its first ``scenes`` scenes.

    Raises:
        BadInput: See :func:`scaling_simulators`.
        PluginBug: A hook of the family raised or gave something else than it should.
    """
    from dataclasses import replace

    from bpb_core.bench.contestants import timed_run
    from bpb_core.registry import make_registry

    reg = registry if registry is not None else make_registry()
    sims = scaling_simulators(reg, result.family, contestants, scenes)
    family = bench_family(reg, result.family)
    sample = family.scenes(scenes, result.seed)
    tallies = {(f, label): _Tally() for f in factors for label in sims}
    if sample and factors:  # untimed: imports and compiled code load before the x1 runs
        warm_up(sims, family.scaled(sample[0], factors[0]))
    for scene in sample:
        for factor in factors:
            busy = family.scaled(scene, factor)
            for label, sim in sims.items():
                try:
                    outcome, spent = timed_run(sim, busy)
                except Exception as exc:  # the simulator's own failure on this scene
                    tallies[factor, label].fail(f"{type(exc).__name__}: {exc}")
                    continue
                tallies[factor, label].add(spent, None, family.events(outcome))
    rows = [_scale_row(f, label, t) for (f, label), t in tallies.items()]
    return replace(result, scaling=rows)


def _scale_row(factor: float, label: str, tally: _Tally) -> ScaleRow:
    ms = 1000 * tally.seconds / tally.runs if tally.runs else None
    events = tally.events / tally.runs if tally.runs else None
    return ScaleRow(factor, label, ms, events, tally.failed, tally.first_error)


def scaling_simulators(
    registry: Registry, family: str, contestants: Sequence[str], scenes: int
) -> dict[str, Simulator]:
    """The simulators of ``--scaling``, checked (the CLI calls this before the
    benchmark, so a bad spec does not wait for it).

    Raises:
        BadInput: Fewer than one scene, a family that does not count events, or a bad spec.
    """
    if scenes < 1:
        raise BadInput(f"--scaling-scenes: must be at least 1, got {scenes}")
    if not isinstance(comparing_family(registry, family), CountsEvents):
        raise BadInput(f"--scaling: scene family {family!r} does not count events")
    specs = [parse_contestant(c, "--scaling") for c in contestants]
    return build_simulators(registry, family, specs, "--scaling")
