"""``bpb bench sim``: simulators of one scene family, speed against error, on the same scenes.

The family (a :class:`~bpb_core.capabilities.Comparing` one) draws the scenes, names the default
contestants and the reference, and says how far an outcome is from the reference's. Contestants
are given as ``name`` or ``name:key=value,...`` (``mysim:dt=0.01``). Every scene is run by the
reference and then by every contestant in turn (interleaved, so machine noise hits all alike);
runs under 5 ms are repeated up to 5 times and the quickest counts. Per contestant the result
holds the mean time per scene, the max and median of the family's ``error`` over scenes and the
sums of its disagreement counts. :mod:`bpb_core.bench.sim_report` turns it into markdown and a plot.
"""

from __future__ import annotations

import math
import statistics
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.bench import machine_description, today
from bpb_core.bench.contestants import (
    build_simulators,
    comparing_family,
    parse_contestant,
    timed_run,
)
from bpb_core.errors import BadInput, PluginError

if TYPE_CHECKING:
    from bpb_core.capabilities import Comparing
    from bpb_core.interfaces import Simulator
    from bpb_core.registry import Registry

ERROR = "error"
"""The key of :meth:`Comparing.compare`'s result that holds the distance to the reference."""

Progress = Callable[[int, int], None]
"""Called with (scenes done, scenes in all) after each scene."""


@dataclass(frozen=True)
class SimRow:
    """One contestant's figures over the benchmark scenes (``counts`` in column order)."""

    name: str
    ms_per_scene: float
    max_error: float
    median_error: float
    counts: dict[str, float]
    reference: bool = False


@dataclass(frozen=True)
class SimBench:
    """The result of :func:`bench_simulators` (``rows``: the reference first)."""

    family: str
    scenes: int
    seed: int
    description: str
    measures: str
    columns: tuple[str, ...]
    rows: list[SimRow]
    simulate_ms: dict[str, float] | None = None
    simulate_scenes: int = 0
    simulate_with: str = ""
    machine: str = field(default_factory=machine_description)
    day: str = field(default_factory=today)


@dataclass
class _Tally:
    seconds: float = 0.0
    errors: list[float] = field(default_factory=list)
    counts: dict[str, float] = field(default_factory=dict)

    def add(self, seconds: float, measures: dict[str, float]) -> None:
        self.seconds += seconds
        self.errors.append(measures[ERROR])
        for key, value in measures.items():
            if key != ERROR:
                self.counts[key] = self.counts.get(key, 0.0) + value

    def row(self, name: str, scenes: int, reference: bool) -> SimRow:
        ms = 1000 * self.seconds / scenes
        mid = statistics.median(self.errors)
        return SimRow(name, ms, max(self.errors), mid, dict(self.counts), reference)


def bench_simulators(
    scenes: int = 100,
    seed: int = 0,
    contestants: Sequence[str] = (),
    reference: str | None = None,
    *,
    family: str | None = None,
    registry: Registry | None = None,
    progress: Progress | None = None,
) -> SimBench:
    """Run the reference and every contestant on ``scenes`` scenes of ``family`` (default: the
    default family) and compare each outcome with the reference's (see the module docstring).

    Raises:
        BadInput: Too few scenes, an unknown or foreign simulator, or a family that cannot
            compare simulators.
    """
    from bpb_core.registry import make_registry

    if scenes < 1:
        raise BadInput(f"--scenes: must be at least 1, got {scenes}")
    reg = registry if registry is not None else make_registry()
    name = family or reg.default_family()
    maker = comparing_family(reg, name)
    ref = parse_contestant(reference or maker.bench_reference)
    others = [parse_contestant(s) for s in (contestants or maker.bench_contestants)]
    sims = build_simulators(reg, name, [ref, *(c for c in others if c.spec != ref.spec)])
    sample = maker.bench_scenes(scenes, seed)
    tallies = _run_all(maker, sims, sample, progress)
    rows = [t.row(label, len(sample), label == ref.spec) for label, t in tallies.items()]
    columns = tuple(rows[0].counts)
    return SimBench(
        name, len(sample), seed, maker.bench_description, maker.bench_measures, columns, rows
    )


def _run_all(
    family: Comparing, sims: dict[str, Simulator], sample: list[Any], progress: Progress | None
) -> dict[str, _Tally]:
    """Each scene through every simulator in turn, the first one's outcome the reference."""
    tallies = {label: _Tally() for label in sims}
    for index, scene in enumerate(sample):
        truth = None
        for label, sim in sims.items():
            outcome, seconds = timed_run(sim, scene)
            truth = outcome if truth is None else truth
            measures = family.compare(outcome, truth, scene)
            if ERROR not in measures:
                raise PluginError(f"scene family: compare() returned no {ERROR!r}")
            tallies[label].add(seconds, measures)
        if progress is not None:
            progress(index + 1, len(sample))
    return tallies


def time_simulate(
    family: Comparing,
    simulator: str,
    count: int = 1000,
    seed: int = 1,
    *,
    registry: Registry | None = None,
    workers: Sequence[int] = (1, 2),
) -> dict[str, float]:
    """Milliseconds per scene of ``bpb simulate``'s library path (read, validate, simulate,
    build and serialise the ground truth) with ``simulator`` (``name:key=value,...``) over
    ``count`` scene files of ``family``, start-up excluded.

    Wall time for each worker count, plus the CPU time of the single-process run (less
    sensitive to other load on a shared machine); three interleaved rounds, the best counts.
    """
    from bpb_core.simulate import simulate_lines

    job = parse_contestant(simulator)
    best: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        paths = _scene_files(family, count, seed, Path(tmp))

        def seconds(files: list[Path], n: int) -> tuple[float, float]:
            wall, cpu = time.perf_counter(), time.process_time()
            for _ in simulate_lines(
                files, simulator=job.name, options=job.options, registry=registry, workers=n
            ):
                pass
            return time.perf_counter() - wall, time.process_time() - cpu

        seconds(paths[:1], 1)  # warm-up
        for _ in range(3):
            for n in workers:
                wall, cpu = seconds(paths, n)
                figures = {f"{n} worker{'s' if n > 1 else ''}, wall": wall}
                figures |= {"1 worker, CPU": cpu} if n == 1 else {}
                for label, value in figures.items():
                    best[label] = min(best.get(label, math.inf), 1000 * value / count)
    return best


def _scene_files(family: Comparing, count: int, seed: int, folder: Path) -> list[Path]:
    """Write ``count`` bench scenes as ``scene_NNNNN.json`` files into ``folder``."""
    paths = []
    for index, scene in enumerate(family.bench_scenes(count, seed)):
        paths.append(folder / f"scene_{index:05d}.json")
        paths[-1].write_text(scene.model_dump_json())
    return paths


def with_simulate_timing(
    result: SimBench, count: int, simulator: str, registry: Registry | None = None
) -> SimBench:
    """``result`` with the ``bpb simulate`` figures for ``simulator`` added."""
    from bpb_core.registry import make_registry

    reg = registry if registry is not None else make_registry()
    family = comparing_family(reg, result.family)
    figures = time_simulate(family, simulator, count, registry=reg)
    return replace(result, simulate_ms=figures, simulate_scenes=count, simulate_with=simulator)
