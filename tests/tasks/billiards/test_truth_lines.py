"""The fast path of ``bpb simulate`` writes the same final.json content as the models do."""

from __future__ import annotations

import json

import pytest

from bpb_tasks.billiards.bench_compare import random_scene
from bpb_tasks.billiards.truth import final_state
from bpb_tasks.billiards.truth_lines import truth_lines
from bpb_tasks.simulators.analytic import AnalyticSimulator
from support.phys_helpers import scene

pytest.importorskip("numba")


def test_fast_lines_equal_the_model_json_on_random_scenes() -> None:
    scenes = [random_scene(21, i, speeds=(0.1, 6.0)) for i in range(200)]
    scenes.append(scene([(0.5, 0.5, 2.0, 0.7), (1.0, 0.6, 0.0, 0.0)], width=3.0, pockets=[]))
    python = AnalyticSimulator(engine="python")
    for horizon in (None, 0.7):
        lines = truth_lines(scenes, AnalyticSimulator(), horizon)
        assert lines is not None and len(lines) == len(scenes)
        for line, s in zip(lines, scenes, strict=True):
            model = final_state(s, python.run(s, horizon)).model_dump_json()
            assert json.loads(line) == json.loads(model)
            assert list(json.loads(line)) == list(json.loads(model))  # same key order


def test_other_simulators_have_no_fast_path() -> None:
    s = random_scene(21, 0)
    assert truth_lines([s], AnalyticSimulator(engine="python"), None) is None
    assert truth_lines([s], AnalyticSimulator(precision=50), None) is None
