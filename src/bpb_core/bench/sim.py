"""``bpb bench sim``: simulators of one scene family, speed against error, on the same scenes.

The family (a :class:`~bpb_core.capabilities.Comparing` one) draws the scenes, names the default
contestants and the reference, and says how far an outcome is from the reference's. Contestants
are given as ``name`` or ``name:key=value,...`` (``mysim:dt=0.01``). Every scene is run by the
reference and then by every contestant in turn (interleaved, so machine noise hits all alike);
runs under 5 ms are repeated up to 5 times and the quickest counts. Per contestant the result
holds the mean time per scene, the max and median of the family's ``error`` over scenes and the
sums of its disagreement counts. :mod:`bpb_core.bench.sim_report` turns it into markdown and a plot.

``--scaling``: a family that counts events (:class:`~bpb_core.capabilities.CountsEvents`) makes
its scenes busier by a factor (more events in the same simulated time); each chosen simulator
runs every scaled scene, the factors interleaved per scene, and per factor the result holds the
mean milliseconds and events per scene. If the cost follows the events, the microseconds per
event stay about flat while the events per scene grow.

In both, a run that raises is a failed scene of that simulator, left out of its figures, and
each simulator runs once untimed first, so loading its imports and compiled code is not timed.
"""

from __future__ import annotations

import contextlib
import math
import statistics
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.bench.comparing import (
    ERROR,
    BenchFamily,
    bench_family,
    build_simulators,
    timed_run,
)
from bpb_core.bench.sim_report import ScaleRow, SimBench, SimRow
from bpb_core.capabilities import RunsMany
from bpb_core.errors import BadInput
from bpb_core.simulator_spec import parse_spec

if TYPE_CHECKING:
    from bpb_core.interfaces import Simulator
    from bpb_core.registry import Registry

Progress = Callable[[int, int], None]
"""Called with (scenes done, scenes in all) after each scene."""
DEFAULT_FACTORS = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0)
"""How much busier ``--scaling`` makes the scenes."""


@dataclass
class _Tally:
    seconds: float = 0.0
    runs: int = 0
    events: int = 0
    errors: list[float] = field(default_factory=list)
    counts: dict[str, float] = field(default_factory=dict)
    batch_ms: float | None = None
    failed: int = 0
    first_error: str = ""

    def add(self, seconds: float, measures: dict[str, float] | None, events: int) -> None:
        self.seconds += seconds
        self.runs += 1
        self.events += events
        if measures is None:
            return
        self.errors.append(measures[ERROR])
        for key, value in measures.items():
            if key != ERROR:
                self.counts[key] = self.counts.get(key, 0.0) + value

    def timed(self, sim: Simulator, scene: Any) -> tuple[Any, float] | None:
        """:func:`timed_run`; ``None`` when the simulator raised (a failed scene)."""
        try:
            return timed_run(sim, scene)
        except Exception as exc:  # the simulator's own failure on this scene
            self.fail(f"{type(exc).__name__}: {exc}")
            return None

    def fail(self, why: str) -> None:
        self.failed += 1
        self.first_error = self.first_error or why

    def row(self, name: str, reference: bool, count_events: bool) -> SimRow:
        ms = 1000 * self.seconds / self.runs if self.runs else None
        high = max(self.errors) if self.errors else None
        mid = statistics.median(self.errors) if self.errors else None
        per_event = 1e6 * self.seconds / self.events if count_events and self.events else None
        return SimRow(
            name, ms, high, mid, dict(self.counts), reference, per_event, self.batch_ms,
            self.failed, self.first_error,
        )  # fmt: skip


def bench_simulators(
    scenes: int = 100,
    seed: int = 0,
    contestants: Sequence[str] = (),
    reference: str | None = None,
    *,
    family: str | None = None,
    registry: Registry | None = None,
    progress: Progress | None = None,
    reference_scenes: int | None = None,
) -> SimBench:
    """Run the reference and every contestant on ``scenes`` scenes of ``family`` (default: the
    default family) and compare each outcome with the reference's (see the module docstring).
    The reference runs on the first ``reference_scenes`` scenes only (default: all); errors and
    disagreements are over those, times over all. A simulator with a batch call
    (:class:`~bpb_core.capabilities.RunsMany`) is also timed on all scenes at once.

    Raises:
        BadInput: Too few scenes, an unknown or foreign simulator, or a family that cannot
            compare simulators.
        PluginBug: A hook of the family raised or gave something else than it should.
    """
    from bpb_core.registry import make_registry

    if scenes < 1:
        raise BadInput(f"--scenes: must be at least 1, got {scenes}")
    if reference_scenes is not None and reference_scenes < 1:
        raise BadInput(f"--reference-scenes: must be at least 1, got {reference_scenes}")
    reg = registry if registry is not None else make_registry()
    name = family or reg.default_family()
    maker = bench_family(reg, name)
    ref = parse_spec(reference or maker.text("bench_reference"), "--reference")
    others = [parse_spec(s, "--contestant") for s in (contestants or maker.contestants())]
    build_simulators(reg, name, [ref], "--reference")
    sims = build_simulators(reg, name, [ref, *(c for c in others if c.spec != ref.spec)])
    sample = maker.scenes(scenes, seed)
    compared = min(len(sample), reference_scenes or len(sample))
    tallies = _run_all(maker, sims, sample, progress, compared)
    _time_batches(sims, sample, tallies)
    counting = maker.counts_events
    rows = [t.row(label, label == ref.spec, counting) for label, t in tallies.items()]
    columns = tuple(next((r.counts for r in rows if r.counts), {}))
    description, measures = maker.text("bench_description"), maker.text("bench_measures")
    return SimBench(
        name, len(sample), seed, description, measures, columns, rows, compared=compared
    )


def _run_all(
    family: BenchFamily,
    sims: dict[str, Simulator],
    sample: list[Any],
    progress: Progress | None,
    compared: int,
) -> dict[str, _Tally]:
    """Each scene through every simulator in turn, the first one's outcome the reference (run
    on the first ``compared`` scenes only). A run that raises, or whose error is not finite,
    is a failed scene of that simulator; a scene the reference failed is compared by none.
    The family's own compare() and events() failing stop the bench (a PluginBug)."""
    tallies = {label: _Tally() for label in sims}
    warm_up(sims, sample[0])
    reference = next(iter(sims))
    for index, scene in enumerate(sample):
        truth = None
        for label, sim in sims.items():
            if label == reference and index >= compared:
                continue
            ran = tallies[label].timed(sim, scene)
            if ran is None:
                continue
            outcome, seconds = ran
            truth = outcome if label == reference else truth
            measures = None if truth is None else family.compare(outcome, truth, scene)
            events = family.events(outcome)
            if measures is not None and not math.isfinite(measures[ERROR]):
                tallies[label].fail(f"{ERROR} {measures[ERROR]!r}")
                continue
            tallies[label].add(seconds, measures, events)
        if progress is not None:
            progress(index + 1, len(sample))
    return tallies


def warm_up(sims: dict[str, Simulator], scene: Any) -> None:
    """Run each simulator once on ``scene``, untimed, so its imports, caches and compiled code
    are loaded before anything is timed (a failing simulator is counted by the timed runs)."""
    for sim in sims.values():
        with contextlib.suppress(Exception):
            sim.run(scene)


def _time_batches(
    sims: dict[str, Simulator], sample: list[Any], tallies: dict[str, _Tally]
) -> None:
    """Per-scene milliseconds of each batch-capable simulator's one call on all scenes (after
    a warm-up call on the first scene)."""
    for label, sim in sims.items():
        if isinstance(sim, RunsMany) and not tallies[label].failed:
            try:
                sim.run_many(sample[:1])
                started = time.perf_counter()
                sim.run_many(sample)
            except Exception:  # no batch figure ("–"); the one-scene figures stand
                continue
            tallies[label].batch_ms = 1000 * (time.perf_counter() - started) / len(sample)


def time_simulate(
    family: BenchFamily, simulator: str, count: int, registry: Registry
) -> dict[str, float]:
    """Milliseconds per scene of ``bpb simulate``'s library path (read, validate, simulate,
    build and serialise the ground truth) with ``simulator`` (``name:key=value,...``) over
    ``count`` scene files of ``family`` (seed 1), start-up excluded.

    Wall time with 1 and 2 workers, plus the CPU time of the single-process run (less
    sensitive to other load on a shared machine); three interleaved rounds, the best counts.
    """
    from bpb_core.simulate import simulate_lines

    job = parse_spec(simulator, "--simulate-with")
    best: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        paths = [Path(tmp) / f"scene_{index:05d}.json" for index in range(count)]
        for path, scene in zip(paths, family.scenes(count, 1), strict=True):
            path.write_text(scene.model_dump_json())

        def seconds(files: list[Path], n: int) -> tuple[float, float]:
            wall, cpu = time.perf_counter(), time.process_time()
            for _ in simulate_lines(
                files, simulator=job.name, options=job.options, registry=registry, workers=n
            ):
                pass
            return time.perf_counter() - wall, time.process_time() - cpu

        # Untimed, on the timed rounds' input: a family's compiled batch path may take only
        # hundreds of scenes at once, so a smaller warm-up left its build or load to round one.
        seconds(paths, 1)
        for _ in range(3):
            for n in (1, 2):
                wall, cpu = seconds(paths, n)
                figures = {f"{n} worker{'s' if n > 1 else ''}, wall": wall}
                figures |= {"1 worker, CPU": cpu} if n == 1 else {}
                for label, value in figures.items():
                    best[label] = min(best.get(label, math.inf), 1000 * value / count)
    return best


def check_simulate_with(registry: Registry, family: str, simulators: Sequence[str]) -> None:
    """Check the ``--simulate-with`` specs before any timing.

    Raises:
        BadInput: A spec is malformed, unknown, of another family or has a bad option.
    """
    specs = [parse_spec(s, "--simulate-with") for s in simulators]
    build_simulators(registry, family, specs, "--simulate-with")


def with_simulate_timing(
    result: SimBench,
    count: int,
    simulators: str | Sequence[str],
    registry: Registry | None = None,
) -> SimBench:
    """``result`` with the ``bpb simulate`` figures for ``simulators`` added (labels prefixed
    with the simulator when there are several)."""
    from bpb_core.registry import make_registry

    reg = registry if registry is not None else make_registry()
    family = bench_family(reg, result.family)
    names = [simulators] if isinstance(simulators, str) else list(simulators)
    check_simulate_with(reg, result.family, names)
    figures: dict[str, float] = {}
    for name in names:
        found = time_simulate(family, name, count, reg)
        prefix = f"{name}, " if len(names) > 1 else ""
        figures |= {f"{prefix}{label}": ms for label, ms in found.items()}
    with_ = ", ".join(names)
    return replace(result, simulate_ms=figures, simulate_scenes=count, simulate_with=with_)


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
                ran = tallies[factor, label].timed(sim, busy)
                if ran is not None:
                    tallies[factor, label].add(ran[1], None, family.events(ran[0]))
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
    if not bench_family(registry, family).counts_events:
        raise BadInput(f"--scaling: scene family {family!r} does not count events")
    specs = [parse_spec(c, "--scaling") for c in contestants]
    return build_simulators(registry, family, specs, "--scaling")
