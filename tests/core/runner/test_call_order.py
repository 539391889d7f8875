"""Calls go out in a seeded random order, so a run stopped early is a uniform sample."""

from __future__ import annotations

import dataclasses
import json
import random
from pathlib import Path

import pytest

from bpb_core.model_calls import ModelRequest, ModelResponse
from bpb_core.registry import Registry
from bpb_core.results import load_results
from bpb_core.results.tables import accuracy
from bpb_core.run_folder import read_attempts
from bpb_core.runner import RetryPolicy, RunOptions, run_eval
from support.runner_scenes import make_dataset

HORIZONS = (1.0, 2.0, 3.0, 4.0, 5.0)


@pytest.fixture(scope="module")
def wide(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Five horizons x 24 scenes."""
    return make_dataset(tmp_path_factory.mktemp("order") / "data", HORIZONS, per=24)


@dataclasses.dataclass
class HalfRight:
    """Right on the even-numbered scenes of every horizon, a non-answer on the others; every
    call costs 1 USD. Its true accuracy is flat: 50% at every horizon."""

    oracle: object
    name: str = "fake:half"

    async def complete(self, request: ModelRequest) -> ModelResponse:
        if int(request.scene.scene_id[-4:]) % 2:
            return ModelResponse("no answer", cost=1.0)
        right: ModelResponse = await self.oracle.complete(request)  # type: ignore[attr-defined]
        return dataclasses.replace(right, cost=1.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_run_stopped_by_max_cost_shows_flat_accuracy_by_horizon(
    wide: Path, tmp_path: Path, registry: Registry, seed: int
) -> None:
    run_dir = tmp_path / "run"
    budget = random.Random(seed).randint(40, 80)  # stop at a random point of 120 calls
    options = RunOptions(
        tasks=("q1",),
        concurrency=1,
        max_cost=budget,
        seed=seed,
        retry=RetryPolicy(max_reasks=0),
    )
    adapter = HalfRight(registry.adapter("baseline:oracle"))
    result = run_eval(wide, adapter, run_dir, options, registry=registry, spec="fake:half")
    assert result.stopped == "max-cost" and result.not_sent == 120 - budget
    table = accuracy(load_results(run_dir, registry=registry).units, view="answered")
    assert list(table["horizon"]) == list(HORIZONS)
    share = budget / 120
    # In dataset order the first horizons would be complete and the last ones empty.
    assert all(abs(c - share) < 0.25 for c in table["completeness"]), table
    assert all(0.25 <= a <= 0.75 for a in table["accuracy"]), list(table["accuracy"])
    manifest = json.loads((run_dir / "run.json").read_text())
    assert manifest["order_seed"] == seed and manifest["stopped"] == "max-cost"


def _sent_order(run_dir: Path) -> list[str]:
    return [f"{e['scene_id']}/{e['task']}" for e in read_attempts(run_dir)]


def test_the_order_is_seeded_mixes_tasks_and_a_resume_keeps_it(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    def run(folder: str, adapter: object = "baseline:oracle", **options: object) -> list[str]:
        chosen = RunOptions(concurrency=1, **options)  # type: ignore[arg-type]
        run_eval(dataset, adapter, tmp_path / folder, chosen, registry=registry)  # type: ignore[arg-type]
        return _sent_order(tmp_path / folder)

    order = run("full", seed=5)
    assert len(order) == 18 and len(set(order)) == 18
    assert order != sorted(order)  # not dataset order
    assert {o.split("/")[1] for o in order[:6]} != {"q1"}  # tasks interleave
    assert run("again", seed=5) == order
    assert run("other", seed=6) != order
    # Stopped after 7 calls, then resumed with another --seed: the run keeps its own order.
    priced = HalfPriced(registry.adapter("baseline:oracle"))
    assert len(run("part", priced, seed=5, max_cost=7)) == 7
    assert run("part", priced, seed=9) == order


@dataclasses.dataclass
class HalfPriced:
    """The oracle at 1 USD a call."""

    oracle: object
    name: str = "fake:priced"

    async def complete(self, request: ModelRequest) -> ModelResponse:
        right: ModelResponse = await self.oracle.complete(request)  # type: ignore[attr-defined]
        return dataclasses.replace(right, cost=1.0)
