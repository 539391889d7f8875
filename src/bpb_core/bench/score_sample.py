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
from bpb_core.errors import BadInput, blamed
from bpb_core.plugin_calls import offered_predictors, prediction
from bpb_core.scored_units import UnitRow, input_frame, scored_units, unit_rows

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
    """A task's scorer, the calls of the sample and their units (scorer input columns).

    Attributes:
        origin: Who supplied the scorer (``Registered.origin``), for one-line plugin errors.
    """

    scorer: Scorer
    cases: list[Case]
    frame: pd.DataFrame = field(repr=False)
    origin: str = ""

    def cut(self) -> list[list[UnitRow]]:
        """Cut every answer of the sample into units (what ``answers -> units`` times; the
        units were checked when the sample was made)."""
        return [self.scorer.units(c.answer, c.truth, c.scene) for c in self.cases]

    def score(self, frame: pd.DataFrame) -> pd.DataFrame:
        """``scorer.score(frame)``, checked like ``bpb report`` checks it.

        Raises:
            PluginBug: The scorer raised or returned the wrong type, naming its plugin.
        """
        scored: pd.DataFrame = scored_units(self.scorer, self.origin, frame)
        return scored

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
    predictor_origin = registry.origin("scene_family", family)
    for entry in dataset:
        key, scene, truth = entry.key, entry.state, entry.truth
        rng = random.Random(f"bench-score:{seed}:{key.horizon!r}:{key.index}")
        outcomes = _outcomes(dataset.family, predictor_origin, scene, truth, rng)
        for name, task in objects.items():
            origin = registry.origin("task", name)
            cases[name] += _answers(task, origin, outcomes, truth, scene, rng)
    samples = {}
    for name, found in cases.items():
        scorer = registry.scorer_for(name)
        origin = registry.scorer_entry(name).origin
        samples[name] = ScoreSample(scorer, found, units_frame(scorer, found, origin), origin)
    return samples


def _outcomes(family: Any, origin: str, scene: Any, truth: Any, rng: random.Random) -> list[Any]:
    """The truth, each predictor's guess and the truth again (to be corrupted)."""
    guesses = []
    if isinstance(family, Predicting):
        names = offered_predictors(family, origin)
        guesses = [prediction(family, origin, name, scene, rng) for name in names]
    return [truth, *guesses, truth]


def _answers(
    task: Task, origin: str, outcomes: list[Any], truth: Any, scene: Any, rng: random.Random
) -> list[Case]:
    found = []
    for position, outcome in enumerate(outcomes):
        if rng.random() < FAILED:
            status = rng.choice(("parse_error", "api_error"))
            found.append(Case(status, None, truth, scene))
            continue
        with blamed(origin, f"task {task.name!r}: expected()"):
            answer = task.expected(outcome)
        if position == len(outcomes) - 1 and rng.random() < CORRUPTED:
            answer = corrupt(answer, rng)
        found.append(Case("ok", answer, truth, scene))
    return found


def units_frame(scorer: Scorer, cases: Sequence[Case], origin: str) -> pd.DataFrame:
    """The units of ``cases`` with the scorer input columns and the scorer's own, typed.

    Raises:
        PluginBug: The scorer's ``units`` raised or returned the wrong type, naming ``origin``.
    """
    cut = [(c.status, unit_rows(scorer, origin, c.answer, c.truth, c.scene)) for c in cases]
    frame: pd.DataFrame = input_frame(scorer, cut)
    return frame
