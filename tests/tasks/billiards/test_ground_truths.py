"""The billiards family's truth of many scenes at once is the truth of each alone."""

from __future__ import annotations

import json

import pytest

from bpb_tasks.billiards.bench_compare import random_scene
from bpb_tasks.billiards.family import BilliardsFamily
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.simulators.analytic import AnalyticSimulator
from support.phys_helpers import scene


def mixed_scenes() -> list[Scene]:
    """Random scenes, some on another table or with fewer balls or unsorted ids, in runs."""
    scenes = []
    for i in range(120):
        data = json.loads(random_scene(21, i, speeds=(0.1, 6.0)).model_dump_json())
        if i % 5 == 2:
            data["balls"] = data["balls"][: 2 + i % 4]
        if i % 3 == 1:
            data["balls"].reverse()
        if 40 <= i < 50 or i == 77:
            data["table"] = {"width": 2.5, "height": 1.25}
        scenes.append(Scene.model_validate(data))
    scenes.append(scene([(0.5, 0.5, 2.0, 0.7), (1.0, 0.6, 0.0, 0.0)], width=3.0, pockets=[]))
    return scenes


@pytest.mark.parametrize("engine", ["auto", "python"])
@pytest.mark.parametrize("horizon", [None, 0.7])
def test_ground_truths_are_each_scene_s_ground_truth(engine: str, horizon: float | None) -> None:
    family, scenes = BilliardsFamily(), mixed_scenes()
    python = AnalyticSimulator(engine="python")
    many = family.ground_truths(scenes, AnalyticSimulator(engine=engine), horizon)
    one = [family.ground_truth(s, python, horizon, stability=False) for s in scenes]
    assert [t.model_dump_json() for t in many] == [t.model_dump_json() for t in one]
    kept = "".join(t.model_dump_json() for t in many)  # the scenes have every case
    assert '"pos":null' in kept and '"kind":"pocket"' in kept and '"kind":"ball"' in kept
    assert '"kind":"wall"' in kept and ('"kind":"stop"' in kept or horizon is not None)


def test_a_batch_outcome_has_the_events_and_positions_of_a_single_run() -> None:
    pytest.importorskip("numba")
    scenes = [random_scene(22, i) for i in range(30)]
    python = AnalyticSimulator(engine="python")
    for got, s in zip(AnalyticSimulator().run_many(scenes), scenes, strict=True):
        want = python.run(s)
        assert (got.horizon, got.positions, got.events) == (
            want.horizon,
            want.positions,
            want.events,
        )
        assert got.segments == {}  # no motion pieces recorded
