"""``bpb bench score``: how fast every installed scorer marks answers.

The units are real: for each scene family with scored tasks a small dataset is generated in a
temporary folder (no images), and each scene is answered, for every task, by the oracle (the
task's expected answer), by each of the family's predictors (when it offers any) and by a
corrupted oracle (one entry of a list dropped or repeated); a share of the calls fail
(``parse_error`` or ``api_error``, no answer). ``Scorer.units`` cuts the answers into units, and
the frame is tiled to the requested number of rows. Then, in turn in one process:

* ``vectorised``: ``Scorer.score`` on the whole frame (target: one million rows within 2 s);
* ``answers -> units``: ``Scorer.units`` over every answer of the sample, scaled to the rows
  (what reading run folders costs per unit, before scoring).
"""

from __future__ import annotations

import functools
import statistics
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from bpb_core.bench.score_sample import HORIZONS, ScoreSample, sample_units, scored_tasks

if TYPE_CHECKING:
    from bpb_core.registry import Registry

TARGET_SECONDS = 2.0
MAX_ROWS = 20_000_000  # the tiled units are held in memory, about 150 bytes a row: 3 GB
Progress = Callable[[str], None]
"""Called with what is being done next (``<task>: timing``)."""


@dataclass(frozen=True)
class ScoreTiming:
    """Wall times (s) of one way of handling ``rows`` units of one task; ``correct`` is the
    share of units marked correct (vectorised scoring only)."""

    task: str
    method: str
    rows: int
    best: float
    median: float
    correct: float | None = None

    @property
    def rows_per_second(self) -> float:
        """Throughput at the best time."""
        return self.rows / self.best if self.best > 0 else float("inf")


def _time(call: Callable[[], object], repeats: int) -> list[float]:
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        call()
        times.append(time.perf_counter() - started)
    return times


def bench_score(
    rows: int = 1_000_000,
    *,
    repeats: int = 5,
    per_horizon: int = 20,
    seed: int = 0,
    registry: Registry | None = None,
    progress: Progress | None = None,
) -> list[ScoreTiming]:
    """Time every installed scorer on ``rows`` real units (see the module docstring), two
    timings per task: vectorised scoring and answers -> units (scaled to ``rows``)."""
    from bpb_core.registry import make_registry

    reg = registry if registry is not None else make_registry()
    timings: list[ScoreTiming] = []
    with tempfile.TemporaryDirectory(prefix="bpb-bench-score-") as tmp:
        for family, tasks in scored_tasks(reg).items():
            if progress is not None:
                progress(f"{family}: generating {len(HORIZONS) * per_horizon} scenes")
            data = Path(tmp) / family
            samples = sample_units(reg, family, tasks, data, per_horizon=per_horizon, seed=seed)
            for task, sample in samples.items():
                if progress is not None:
                    progress(f"{task}: timing")
                timings += _timings(task, sample, rows, repeats)
    return timings


def _timings(task: str, sample: ScoreSample, rows: int, repeats: int) -> list[ScoreTiming]:
    frame = sample.tiled(rows)
    sample.score(frame.head(1000))  # checked; warms caches and lazy imports
    share = float(sample.score(frame)["correct"].mean())  # checked on every row once
    vector = _time(functools.partial(sample.scorer.score, frame), repeats)  # timed bare
    cut = _time(sample.cut, max(1, repeats // 2))
    scale = rows / max(len(sample.frame), 1)
    return [
        ScoreTiming(task, "vectorised", rows, min(vector), statistics.median(vector), share),
        ScoreTiming(
            task,
            "answers -> units (scaled)",
            rows,
            min(cut) * scale,
            statistics.median(cut) * scale,
        ),
    ]


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
    from bpb_core.dataset.scene_entry import clear_truth_cache
    from bpb_core.results import load_results

    clear_truth_cache()
    started = time.perf_counter()
    results = load_results(run_dirs)
    cold = time.perf_counter() - started
    started = time.perf_counter()
    load_results(run_dirs)
    warm = time.perf_counter() - started
    answers = int((results.calls["status"] != "missing").sum())
    return LoadTiming(answers, len(results.units), cold, warm)
