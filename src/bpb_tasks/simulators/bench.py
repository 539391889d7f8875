"""``bpb bench sim``: speed against error of the simulators, side by side on the same scenes.

Every scene is run by every contestant in turn (interleaved, so machine noise hits all alike;
runs under 5 ms are repeated up to 5 times and the quickest counts) and
compared with the 50-digit mpmath run of the analytic simulator: final-position error (per scene
the largest error over the balls on the table in both; then max and median over scenes) and the
number of scenes whose Q1 contacts, Q2 walls or pocketed set differ from the reference.
"""

from __future__ import annotations

import math
import platform
import statistics
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import date
from pathlib import Path

from bpb_core.interfaces import Simulator
from bpb_tasks.billiards.outcome import Outcome
from bpb_tasks.billiards.scene import Scene
from bpb_tasks.billiards.stability import labels
from bpb_tasks.simulators.analytic import AnalyticSimulator
from bpb_tasks.simulators.bench_scenes import random_scenes
from bpb_tasks.simulators.pymunk_sim import PymunkSimulator

Progress = Callable[[str, int, int], None]


@dataclass(frozen=True)
class SimRow:
    """One contestant's figures over the benchmark scenes."""

    name: str
    ms_per_scene: float
    max_error: float
    median_error: float
    q1_disagree: int
    q2_disagree: int
    pocket_disagree: int
    q3_wrong: int


@dataclass(frozen=True)
class SimBench:
    """The result of :func:`bench_simulators`."""

    scenes: int
    seed: int
    rows: list[SimRow]
    simulate_ms: dict[str, float] | None = None
    simulate_scenes: int = 0
    machine: str = field(default_factory=lambda: machine_description())
    day: str = field(default_factory=lambda: date.today().isoformat())


def machine_description() -> str:
    """``2 cores, <CPU model>, CPython 3.11.7`` for the figures' record."""
    import os

    model = "unknown CPU"
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    python = f"{platform.python_implementation()} {platform.python_version()}"
    return f"{os.cpu_count()} cores, {model}, {python}"


def contestants(dts: Sequence[float]) -> dict[str, Simulator]:
    """analytic float64, analytic mpmath (the reference, timed too) and pymunk at each dt."""
    sims: dict[str, Simulator] = {"analytic": AnalyticSimulator()}
    sims.update({f"pymunk dt={dt:g}": PymunkSimulator(dt=dt) for dt in dts})
    return sims


def bench_simulators(
    scenes: int = 100,
    seed: int = 0,
    dts: Sequence[float] = (1e-2, 1e-3, 1e-4),
    progress: Progress | None = None,
) -> SimBench:
    """Run every contestant on ``scenes`` random 7-ball scenes and compare with the reference."""
    reference = AnalyticSimulator(precision=50)
    sims = {"mpmath50 (reference)": reference, **contestants(dts)}
    times: dict[str, float] = dict.fromkeys(sims, 0.0)
    errors: dict[str, list[float]] = {name: [] for name in sims}
    flips: dict[str, list[int]] = {name: [0, 0, 0] for name in sims}
    wrong: dict[str, int] = dict.fromkeys(sims, 0)
    sample = list(random_scenes(scenes, seed=seed))
    for index, scene in enumerate(sample):
        truth: Outcome | None = None
        for name, sim in sims.items():
            outcome, seconds = timed_run(sim, scene)
            times[name] += seconds
            truth = outcome if truth is None else truth
            errors[name].append(position_error(outcome, truth))
            wrong[name] += q3_wrong(outcome, truth, scene.physics.ball_radius)
            for k, (a, b) in enumerate(zip(labels(outcome), labels(truth), strict=True)):
                flips[name][k] += a != b
        if progress is not None:
            progress("scenes", index + 1, len(sample))
    rows = [
        SimRow(
            name,
            1000 * times[name] / len(sample),
            max(errors[name]),
            statistics.median(errors[name]),
            flips[name][0],
            flips[name][1],
            flips[name][2],
            wrong[name],
        )
        for name in sims
    ]
    return SimBench(scenes, seed, rows)


def timed_run(sim: Simulator, scene: Scene, budget: float = 0.005) -> tuple[Outcome, float]:
    """Run ``sim`` on ``scene``; fast runs are repeated (up to 5 times, within ``budget``
    seconds) and the quickest counts, so a preempted sub-millisecond run does not dominate."""
    best, spent, runs = math.inf, 0.0, 0
    while runs < 5 and (runs == 0 or spent < budget):
        started = time.perf_counter()
        outcome = sim.run(scene)
        seconds = time.perf_counter() - started
        best, spent, runs = min(best, seconds), spent + seconds, runs + 1
    return outcome, best


def q3_wrong(outcome: Outcome, truth: Outcome, radius: float) -> int:
    """Balls that Q3 scoring would mark wrong: more than ``R`` off, or pocketed in one only."""
    count = 0
    for ball, q in truth.positions.items():
        p = outcome.positions.get(ball)
        if (p is None) != (q is None) or (
            p is not None and q is not None and math.dist(p, q) > radius
        ):
            count += 1
    return count


def position_error(outcome: Outcome, truth: Outcome) -> float:
    """Largest distance between final positions of balls on the table in both."""
    gaps = [
        math.dist(p, q)
        for ball, q in truth.positions.items()
        if q is not None and (p := outcome.positions.get(ball)) is not None
    ]
    return max(gaps, default=0.0)


def time_simulate(
    count: int = 1000, seed: int = 1, workers: Sequence[int] = (1, 2)
) -> dict[str, float]:
    """Milliseconds per scene of ``bpb simulate``'s library path (read, validate, simulate,
    build and serialise final.json) over ``count`` scene files, start-up excluded.

    Wall time for each worker count, plus the CPU time of the single-process run (less
    sensitive to other load on a shared machine); three interleaved rounds, the best counts.
    """
    from bpb_core.simulate import simulate_lines

    best: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for index, scene in enumerate(random_scenes(count, seed=seed)):
            path = Path(tmp) / f"scene_{index:05d}.json"
            path.write_text(scene.model_dump_json())
            paths.append(path)
        simulator = AnalyticSimulator()
        for _ in simulate_lines(paths[:1], simulator=simulator, workers=1):  # warm-up
            pass
        for _ in range(3):
            for n in workers:
                wall, cpu = time.perf_counter(), time.process_time()
                for _ in simulate_lines(paths, simulator=simulator, workers=n):
                    pass
                figures = {f"{n} worker{'s' if n > 1 else ''}, wall": time.perf_counter() - wall}
                if n == 1:
                    figures["1 worker, CPU"] = time.process_time() - cpu
                for label, seconds in figures.items():
                    best[label] = min(best.get(label, math.inf), 1000 * seconds / count)
    return best


def with_simulate_timing(result: SimBench, count: int) -> SimBench:
    """``result`` with the ``bpb simulate`` figures added."""
    from dataclasses import replace

    return replace(result, simulate_ms=time_simulate(count), simulate_scenes=count)
