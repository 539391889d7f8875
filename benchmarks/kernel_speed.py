"""The compiled kernel itself against the pure-Python engine, side by side on the same scenes.

Usage: ``python benchmarks/kernel_speed.py [COUNT] [ROUNDS]`` (default 10,000 ``bpb bench sim``
scenes, seed 0, 3 rounds). Per round, interleaved: the Python engine scene by scene
(``AnalyticSimulator(engine="python").run``), the kernel's batch entry point on arrays prepared
beforehand (``run_many_arrays``: the compiled event loop alone), ``outcomes_many`` (arrays built
from the scene models and labels and final positions read back) and the kernel scene by scene
(``AnalyticSimulator(engine="kernel").run``, an ``Outcome`` with events and segments per scene).
CPU seconds (``time.process_time``); the best round counts.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from bpb_tasks.billiards.bench_compare import random_scenes
from bpb_tasks.simulators.analytic import AnalyticSimulator
from bpb_tasks.simulators.analytic.kernel import (
    outcomes_many,
    run_many_arrays,
    scene_arrays,
    table_params,
)


def main(count: int, rounds: int) -> None:
    """Print µs per scene and per event of each way, and the speed-ups."""
    scenes = list(random_scenes(count, 0))
    python, kernel = AnalyticSimulator(engine="python"), AnalyticSimulator(engine="kernel")
    arrays = [scene_arrays(s) for s in scenes]
    starts = np.cumsum([0] + [len(a[0]) for a in arrays])
    pos, vel = np.concatenate([a[1] for a in arrays]), np.concatenate([a[2] for a in arrays])
    prm, pockets = table_params(scenes[0])
    ends = np.array([s.horizon for s in scenes])
    events = sum(len(python.run(s).events) for s in scenes[:2000]) * count / min(count, 2000)
    ways = {
        "python engine, per scene": lambda: [python.run(s) for s in scenes],
        "kernel alone (run_many_arrays)": lambda: run_many_arrays(
            pos, vel, starts, prm, pockets, ends, 100_000
        ),
        "outcomes_many (models in, outcomes out)": lambda: outcomes_many(scenes),
        "kernel, per scene (Outcome)": lambda: [kernel.run(s) for s in scenes],
    }
    outcomes_many(scenes[:10])
    best = dict.fromkeys(ways, float("inf"))
    for _ in range(rounds):
        for name, way in ways.items():
            started = time.process_time()
            way()
            best[name] = min(best[name], time.process_time() - started)
    base = best["python engine, per scene"]
    print(f"{count} scenes, about {events / count:.1f} events per scene")
    for name, seconds in best.items():
        print(
            f"{name}: {1e6 * seconds / count:.1f} µs/scene, {1e6 * seconds / events:.2f} µs/event,"
            f" {base / seconds:.1f}x the python engine"
        )


if __name__ == "__main__":
    args = [int(a) for a in sys.argv[1:3]]
    main(*(args + [10_000, 3][len(args) :]))
