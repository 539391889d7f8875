"""Real scored units for ``bpb bench score``, from a small generated dataset.

Every scene of the dataset is answered, for every task, by the oracle, by each of the family's
predictors and by a corrupted oracle; :data:`FAILED` of the calls fail with no answer. Each
scene's choices come from a generator seeded from (seed, horizon, index).
"""

from __future__ import annotations

import copy
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from bpb_core.capabilities import Predicting
from bpb_core.errors import BadInput
from bpb_core.scored_units import SCORER_INPUT, UnitRow

if TYPE_CHECKING:
    from bpb_core.interfaces import Scorer, Task
    from bpb_core.registry import Registry

HORIZONS = (1.0, 2.0, 3.0, 4.0, 5.0)
FAILED = 0.1
"""Share of calls that fail (half ``parse_error``, half ``api_error``), leaving no answer."""
CORRUPTED = 0.5
"""Share of the corrupted-oracle answers that are actually corrupted (the rest stay exact)."""


@dataclass(frozen=True)
class Case:
    """One call to score: its status, its answer (``None``: none) and the scene it is about."""

    status: str
    answer: dict[str, Any] | None
    truth: Any
    scene: Any


@dataclass(frozen=True)
class ScoreSample:
    """A task's scorer, the calls of the sample and their units (scorer input columns)."""

    scorer: Scorer
    cases: list[Case]
    frame: pd.DataFrame = field(repr=False)

    def cut(self) -> list[list[UnitRow]]:
        """Cut every answer of the sample into units (what ``answers -> units`` times)."""
        return [self.scorer.units(c.answer, c.truth, c.scene) for c in self.cases]

    def tiled(self, rows: int) -> pd.DataFrame:
        """The units repeated (and cut) to exactly ``rows`` rows, with a fresh index."""
        picks = np.resize(np.arange(len(self.frame)), rows)
        return self.frame.iloc[picks].reset_index(drop=True)


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


def corrupt(answer: Mapping[str, Any], rng: random.Random) -> dict[str, Any]:
    """A copy of ``answer`` with one entry of one of its lists dropped or repeated."""
    out = copy.deepcopy(dict(answer))
    lists = [key for key, value in out.items() if isinstance(value, list) and value]
    if lists:
        items = out[rng.choice(lists)]
        index = rng.randrange(len(items))
        if rng.random() < 0.5:
            del items[index]
        else:
            items.append(copy.deepcopy(items[index]))
    return out


def sample_units(
    registry: Registry,
    family: str,
    tasks: Sequence[str],
    data: Path,
    *,
    per_horizon: int = 20,
    seed: int = 0,
) -> dict[str, ScoreSample]:
    """Generate ``per_horizon`` scenes per horizon of ``family`` into ``data`` (no images) and
    answer them for each of ``tasks`` (see the module docstring)."""
    from bpb_core.dataset import generate_dataset, load_dataset

    generate_dataset(
        data, per_horizon, HORIZONS, seed, family=family, images=False, workers=1, registry=registry
    )
    dataset = load_dataset(data, registry=registry)
    objects = {name: registry.task(name) for name in tasks}
    cases: dict[str, list[Case]] = {name: [] for name in tasks}
    for entry in dataset:
        key, scene, truth = entry.key, entry.state, entry.truth
        rng = random.Random(f"bench-score:{seed}:{key.horizon!r}:{key.index}")
        outcomes = _outcomes(dataset.family, scene, truth, rng)
        for name, task in objects.items():
            cases[name] += _answers(task, outcomes, truth, scene, rng)
    samples = {}
    for name, found in cases.items():
        scorer = registry.scorer_for(name)
        samples[name] = ScoreSample(scorer, found, units_frame(scorer, found))
    return samples


def _outcomes(family: Any, scene: Any, truth: Any, rng: random.Random) -> list[Any]:
    """The truth, each predictor's guess and the truth again (to be corrupted)."""
    guesses = []
    if isinstance(family, Predicting):
        guesses = [family.predict(name, scene, rng) for name in family.predictors]
    return [truth, *guesses, truth]


def _answers(
    task: Task, outcomes: list[Any], truth: Any, scene: Any, rng: random.Random
) -> list[Case]:
    found = []
    for position, outcome in enumerate(outcomes):
        if rng.random() < FAILED:
            status = rng.choice(("parse_error", "api_error"))
            found.append(Case(status, None, truth, scene))
            continue
        answer = task.expected(outcome)
        if position == len(outcomes) - 1 and rng.random() < CORRUPTED:
            answer = corrupt(answer, rng)
        found.append(Case("ok", answer, truth, scene))
    return found


def units_frame(scorer: Scorer, cases: Sequence[Case]) -> pd.DataFrame:
    """The units of ``cases`` with the scorer input columns and the scorer's own, typed."""
    columns: dict[str, list[Any]] = {name: [] for name in (*SCORER_INPUT, *scorer.columns)}
    for case in cases:
        rows = scorer.units(case.answer, case.truth, case.scene)
        columns["status"] += [case.status] * len(rows)
        for position, name in enumerate(("unit", "truth", "pred", "duplicate")):
            columns[name] += [row[position] for row in rows]
        for position, name in enumerate(scorer.columns):
            columns[name] += [row.values[position] for row in rows]
    dtypes = {**SCORER_INPUT, **scorer.columns}
    return pd.DataFrame({name: pd.Series(v, dtype=dtypes[name]) for name, v in columns.items()})
