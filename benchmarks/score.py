"""Scoring speed of every installed scorer on real answers.

Usage: ``python benchmarks/score.py [--rows N] [--repeats N] [--per-horizon N] [--runs DIR ...]``.
For each scene family with scored tasks a small dataset is generated in a temporary folder (no
images), and each scene is answered, for every task, by the oracle (the task's expected answer),
by each of the family's predictors and by a corrupted oracle (one entry of a list dropped or
repeated, half the time); a tenth of the calls fail (``parse_error`` or ``api_error``, no
answer). ``Scorer.units`` cuts the answers into units and the frame is tiled to ``--rows``
rows. Timed per task, best and median of ``--repeats``:

* ``vectorised``: ``Scorer.score`` on the whole frame (target: one million rows within 2 s);
* ``answers -> units``: ``Scorer.units`` over every answer of the sample, scaled to the rows.

``--runs`` also times ``load_results`` on run folders, cold and warm. Exits 1 when vectorised
scoring misses the target.
"""

from __future__ import annotations

import argparse
import copy
import random
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from bpb_core import BadInput, Registry, generate_dataset, load_dataset, load_results, make_registry
from bpb_core.capabilities import Predicting
from bpb_core.plugin_calls import offered_predictors, prediction
from bpb_core.scored_units import input_frame, scored_units, unit_rows

TARGET_SECONDS = 2.0
HORIZONS = (1.0, 2.0, 3.0, 4.0, 5.0)
FAILED = 0.1


def scored_tasks(registry: Registry) -> dict[str, list[str]]:
    """Installed tasks that have a scorer, by the scene family they ask about."""
    found: dict[str, list[str]] = {}
    for name in registry.names("task"):
        try:
            registry.scorer_for(name)
        except BadInput:
            continue
        family = registry.task_info(name).family or registry.default_family()
        found.setdefault(family, []).append(name)
    return found


def corrupt(answer: dict[str, Any], rng: random.Random) -> dict[str, Any]:
    """A copy of ``answer`` with one entry of one of its lists dropped or repeated."""
    out = copy.deepcopy(answer)
    lists = [key for key, value in out.items() if isinstance(value, list) and value]
    if lists:
        items = out[rng.choice(lists)]
        index = rng.randrange(len(items))
        if rng.random() < 0.5:
            del items[index]
        else:
            items.append(copy.deepcopy(items[index]))
    return out


Call = tuple[str, Any, Any, Any]
"""One answered call: status, answer (None: none), truth, scene."""


def answered(
    registry: Registry, family: str, tasks: list[str], data: Path, per_horizon: int
) -> dict[str, list[Call]]:
    """Per task: the calls about a fresh dataset of ``family`` in ``data``."""
    generate_dataset(data, per_horizon, HORIZONS, 0, family=family, images=False, workers=1)
    dataset = load_dataset(data, registry=registry)
    origin = registry.origin("scene_family", family)
    calls: dict[str, list[Call]] = {name: [] for name in tasks}
    for entry in dataset:
        key, scene, truth = entry.key, entry.state, entry.truth
        rng = random.Random(f"bench-score:0:{key.horizon!r}:{key.index}")
        guesses = []
        if isinstance(dataset.family, Predicting):
            names = offered_predictors(dataset.family, origin)
            guesses = [prediction(dataset.family, origin, n, scene, rng) for n in names]
        outcomes = [truth, *guesses, truth]
        for name in tasks:
            task = registry.task(name)
            for position, outcome in enumerate(outcomes):
                if rng.random() < FAILED:
                    failure = rng.choice(("parse_error", "api_error"))
                    calls[name].append((failure, None, truth, scene))
                    continue
                answer = task.expected(outcome)
                if position == len(outcomes) - 1 and rng.random() < 0.5:
                    answer = corrupt(answer, rng)
                calls[name].append(("ok", answer, truth, scene))
    return calls


def times(call: Callable[[], object], repeats: int) -> list[float]:
    found = []
    for _ in range(repeats):
        started = time.perf_counter()
        call()
        found.append(time.perf_counter() - started)
    return found


def bench_task(registry: Registry, task: str, calls: list[Call], rows: int, repeats: int) -> bool:
    """Print the two timings of ``task``; True when vectorised scoring is within the target."""
    scorer, origin = registry.scorer_for(task), registry.scorer_entry(task).origin

    def cut() -> list[Any]:
        return [(status, unit_rows(scorer, origin, *rest)) for status, *rest in calls]

    frame = input_frame(scorer, cut())
    tiled = frame.iloc[np.resize(np.arange(len(frame)), rows)].reset_index(drop=True)
    share = float(scored_units(scorer, origin, tiled)["correct"].mean())  # checked once
    vector = times(lambda: scorer.score(tiled), repeats)
    scale = rows / max(len(frame), 1)
    units = [t * scale for t in times(cut, max(1, repeats // 2))]
    for method, found in (("vectorised", vector), ("answers -> units (scaled)", units)):
        best, middle = min(found), statistics.median(found)
        print(f"{task:12}{method:28}{rows:>12,}{best:10.3f}{middle:10.3f}{rows / best:>14,.0f}"
              + (f"{100 * share:9.1f}%" if method == "vectorised" else ""))  # fmt: skip
    return min(vector) <= TARGET_SECONDS


def bench_load(run_dirs: list[str]) -> None:
    """Print the cold and warm time of ``load_results`` on ``run_dirs``."""
    started = time.perf_counter()
    results = load_results(run_dirs)
    cold = time.perf_counter() - started
    started = time.perf_counter()
    load_results(run_dirs)
    warm = time.perf_counter() - started
    answers = int((results.calls["status"] != "missing").sum())
    print(f"load_results: {answers:,} answer files, {len(results.units):,} units: {cold:.2f} s "
          f"cold, {warm:.2f} s warm ({answers / cold:,.0f} files/s cold)")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000, help="unit rows per scorer")
    parser.add_argument("--repeats", type=int, default=5, help="timed repeats")
    parser.add_argument("--per-horizon", type=int, default=20, help="scenes per horizon (x5)")
    parser.add_argument("--runs", nargs="*", default=[], help="also time reading these runs")
    args = parser.parse_args()
    registry = make_registry()
    print(f"Scoring speed (target: {args.rows:,} rows in at most {TARGET_SECONDS:g} s)")
    print(f"{'task':12}{'method':28}{'rows':>12}{'best s':>10}{'median s':>10}{'rows/s':>14}"
          f"{'correct':>10}")  # fmt: skip
    fast = True
    with tempfile.TemporaryDirectory(prefix="bpb-bench-score-") as tmp:
        for family, tasks in scored_tasks(registry).items():
            calls = answered(registry, family, tasks, Path(tmp) / family, args.per_horizon)
            for task in tasks:
                fast &= bench_task(registry, task, calls[task], args.rows, max(1, args.repeats))
    if args.runs:
        bench_load(args.runs)
    sys.exit(0 if fast else 1)


if __name__ == "__main__":
    main()
