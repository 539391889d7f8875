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

:class:`BenchFamily` runs each hook of the family under :func:`~bpb_core.errors.blamed` and
checks what it gives, so a family's mistake is one line naming its plugin
(:class:`~bpb_core.errors.PluginBug`, exit 3) instead of a traceback, a wrong figure, or a
failure counted against the simulator whose outcome the family was looking at.
"""

from __future__ import annotations

import contextlib
import math
import numbers
import statistics
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.bench.sim_report import ScaleRow, SimBench, SimRow
from bpb_core.capabilities import Comparing, CountsEvents, RunsMany
from bpb_core.errors import BadInput, PluginBug, blamed
from bpb_core.plugin_calls import family_label, family_model
from bpb_core.simulator_spec import parse_spec

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
