"""How fast the scorers mark answers: vectorised ``Scorer.score`` beside a per-row Python loop.

A synthetic frame of scored units (the columns of :data:`bpb_core.scored_units.SCORER_INPUT`, with a
realistic mix of statuses, missing, invalid and duplicate predictions) is scored by every
registered built-in scorer. The per-row loop applies the same rules one row at a time on a
smaller sample and is scaled up, to show what vectorising buys. Target: one million rows in at
most two seconds per scorer.
"""

from __future__ import annotations

import functools
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bpb_core.scored_units import SCORER_INPUT

TARGET_SECONDS = 2.0
_P_Q3 = [0.85, 0.08, 0.02, 0.05]
_P_LABEL = [0.3, 0.6, 0.05, 0.05]


@dataclass(frozen=True)
class ScoreTiming:
    """Wall times (s) of one way of scoring ``rows`` rows of one task."""

    task: str
    method: str
    rows: int
    best: float
    median: float

    @property
    def rows_per_second(self) -> float:
        """Throughput at the best time."""
        return self.rows / self.best if self.best > 0 else float("inf")


def synthetic_units(task: str, rows: int, seed: int = 0) -> pd.DataFrame:
    """``rows`` random units of ``task`` with the scorer input columns and dtypes."""
    rng = np.random.default_rng([seed, rows, sum(map(ord, task))])
    status = rng.choice(["ok", "parse_error", "api_error"], rows, p=[0.9, 0.05, 0.05])
    if task == "q3":
        truth = rng.choice(["pos", "null"], rows, p=[0.9, 0.1])
        pred = rng.choice(np.array(["pos", "null", "?", None], dtype=object), rows, p=_P_Q3)
    else:
        truth = rng.choice(["T", "F"], rows, p=[0.3, 0.7])
        pred = rng.choice(np.array(["T", "F", "?", None], dtype=object), rows, p=_P_LABEL)
    tx, ty = rng.uniform(0.03, 1.97, rows), rng.uniform(0.03, 0.97, rows)
    px, py = tx + rng.normal(0, 0.03, rows), ty + rng.normal(0, 0.03, rows)
    is_pos = (truth == "pos") if task == "q3" else np.zeros(rows, dtype=bool)
    pred_pos = (pred == "pos") if task == "q3" else np.zeros(rows, dtype=bool)
    data: dict[str, Any] = {
        "status": status,
        "unit": rng.integers(0, 7, rows).astype(str),
        "truth": truth,
        "pred": pred,
        "duplicate": rng.random(rows) < 0.01,
        "truth_x": np.where(is_pos, tx, np.nan),
        "truth_y": np.where(is_pos, ty, np.nan),
        "pred_x": np.where(pred_pos, px, np.nan),
        "pred_y": np.where(pred_pos, py, np.nan),
        "start_x": tx,
        "start_y": ty,
        "radius": np.full(rows, 0.028575),
    }
    return pd.DataFrame(data).astype(SCORER_INPUT)


def _loop_correct(frame: pd.DataFrame, task: str) -> list[bool]:
    """The same rules, one row at a time (the baseline that vectorising replaces)."""
    cols: list[list[Any]] = [frame[c].tolist() for c in LOOP_COLUMNS]
    out = []
    for status, dup, truth, pred, tx, ty, px, py, radius in zip(*cols, strict=True):
        ok = status == "ok" and not dup
        if task == "q3":
            both_null = truth == "null" and pred == "null"
            d = ((px - tx) ** 2 + (py - ty) ** 2) ** 0.5
            out.append(ok and (both_null or d <= radius))
        else:
            out.append(ok and pred == truth)
    return out


LOOP_COLUMNS = (
    "status",
    "duplicate",
    "truth",
    "pred",
    "truth_x",
    "truth_y",
    "pred_x",
    "pred_y",
    "radius",
)


def _time(call: Callable[[], object], repeats: int) -> list[float]:
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        call()
        times.append(time.perf_counter() - started)
    return times


def bench_score(
    rows: int = 1_000_000, *, repeats: int = 5, loop_rows: int = 50_000, seed: int = 0
) -> list[ScoreTiming]:
    """Time every built-in scorer on ``rows`` units, beside a per-row loop on ``loop_rows``
    (reported scaled to ``rows``). Scorers and loop are timed in the same process, in turn."""
    from bpb_core.registry import make_registry

    registry = make_registry()
    timings: list[ScoreTiming] = []
    for task in ("q1", "q2", "q3"):
        (found,) = registry.scorers_for(task)[:1]
        scorer = registry.scorer(found.info.name)
        frame = synthetic_units(task, rows, seed)
        small = frame.head(loop_rows)
        scorer.score(frame.head(1000))  # warm caches and lazy imports
        vector = _time(functools.partial(scorer.score, frame), repeats)
        loop = _time(functools.partial(_loop_correct, small, task), max(1, repeats // 2))
        scale = rows / max(len(small), 1)
        timings.append(
            ScoreTiming(task, "vectorised", rows, min(vector), statistics.median(vector))
        )
        timings.append(
            ScoreTiming(
                task,
                "per-row loop (scaled)",
                rows,
                min(loop) * scale,
                statistics.median(loop) * scale,
            )
        )
        timings.append(_explode_timing(scorer, task, rows, repeats))
    return timings


def _explode_timing(
    scorer: Any, task: str, rows: int, repeats: int, answers: int = 2000
) -> ScoreTiming:
    """Time ``Scorer.units`` (answer dict -> unit rows), scaled to ``rows`` unit rows. This runs
    once per answer file while results are loaded, before the vectorised scoring."""
    from bpb_core.registry import make_registry
    from bpb_tasks.billiards.scene import Ball, Scene
    from bpb_tasks.billiards.truth import final_state

    balls = [Ball(id=k, pos=(0.3 + 0.2 * k, 0.5)) for k in range(7)]
    balls[0] = Ball(id=0, pos=(0.3, 0.5), vel=(0.5, 0.1))
    scene = Scene(scene_id="h1_0000", horizon=1.0, balls=balls)
    registry = make_registry()
    final = final_state(scene, registry.simulator("analytic").run(scene))
    answer = registry.task(task).expected(final)
    per_answer = len(scorer.units(answer, final, scene))

    def explode() -> None:
        for _ in range(answers):
            scorer.units(answer, final, scene)

    times = _time(explode, max(1, repeats // 2))
    scale = rows / (answers * per_answer)
    best, mid = min(times) * scale, statistics.median(times) * scale
    return ScoreTiming(task, "answers -> units (scaled)", rows, best, mid)


@dataclass(frozen=True)
class LoadTiming:
    """Reading and scoring run folders: answer files, unit rows, seconds (cold and warm)."""

    answers: int
    units: int
    cold: float
    warm: float


def bench_load(run_dirs: list[str]) -> LoadTiming:
    """Time :func:`bpb_core.results.load_results` on ``run_dirs``: cold (ground truth not yet
    cached in this process) and warm (a second read)."""
    from bpb_core.results import load_results
    from bpb_core.results.reading import read_truth

    read_truth.cache_clear()
    started = time.perf_counter()
    results = load_results(run_dirs)
    cold = time.perf_counter() - started
    started = time.perf_counter()
    load_results(run_dirs)
    warm = time.perf_counter() - started
    answers = int((results.calls["status"] != "missing").sum())
    return LoadTiming(answers, len(results.units), cold, warm)
