"""Check the compiled kernel against the pure-Python engine on many random scenes.

Usage: ``python benchmarks/check_kernel.py [COUNT] [SEED]`` (default 100,000 scenes, seed 2026).
Scenes are sampled as in ``tests/tasks/simulators/test_kernel.py`` (horizons 1-5 s, cue speeds
0.2-12 m/s). Prints label differences, the largest position difference and timings.
"""

from __future__ import annotations

import math
import sys
import time

from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.billiards.scene.sampler import build_scene, draw, scene_rng
from bpb_tasks.simulators.analytic import AnalyticSimulator
from bpb_tasks.simulators.analytic.kernel import outcomes_many


def main(count: int, seed: int = 2026, chunk: int = 2000) -> None:
    """Compare ``count`` scenes in chunks; print the figures."""
    cfg, python = DatasetConfig(), AnalyticSimulator(engine="python")
    diffs = worst = events = 0.0
    t_kernel = t_python = 0.0
    for start in range(0, count, chunk):
        scenes = []
        for i in range(start, min(start + chunk, count)):
            horizon = float(1 + i % 5)
            d = draw(scene_rng(seed, horizon, i), cfg)
            scenes.append(build_scene(d, horizon, i, cfg, speed=0.2 + 11.8 * d.u))
        t0 = time.perf_counter()
        batch = outcomes_many(scenes)
        t_kernel += time.perf_counter() - t0
        for k, s in enumerate(scenes):
            t0 = time.perf_counter()
            ref = python.run(s)
            t_python += time.perf_counter() - t0
            events += len(ref.events)
            same = (
                batch[k].cue_contacts() == ref.cue_contacts()
                and batch[k].cue_walls() == ref.cue_walls()
            )
            for ball, pos in ref.positions.items():
                other = batch[k].positions[ball]
                if (pos is None) != (other is None):
                    same = False
                elif pos is not None and other is not None:
                    worst = max(worst, math.dist(pos, other))
            diffs += not same
        print(f"{start + len(scenes)} scenes: {int(diffs)} label differences, max {worst:.3g} m")
    print(
        f"{count} scenes, {int(events)} events: {int(diffs)} label differences, "
        f"max position difference {worst:.3g} m; kernel {t_kernel:.1f} s, python {t_python:.1f} s"
    )


if __name__ == "__main__":
    args = [int(a) for a in sys.argv[1:3]]
    main(*(args or [100_000]))
