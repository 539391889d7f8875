"""The fast path of ``bpb simulate`` writes the same final.json content as the models do."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

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
            assert line == model  # same bytes as the model path


def test_other_simulators_have_no_fast_path() -> None:
    s = random_scene(21, 0)
    assert truth_lines([s], AnalyticSimulator(engine="python"), None) is None
    assert truth_lines([s], AnalyticSimulator(precision=50), None) is None


def test_texts_are_read_without_models_only_when_plainly_valid() -> None:
    import math

    from hypothesis import given, settings, strategies as st

    from bpb_tasks.billiards.scene import Scene
    from bpb_tasks.billiards.scene_text import light_scene

    base = json.loads(random_scene(21, 3).model_dump_json())

    @settings(max_examples=300, deadline=None)
    @given(
        st.sampled_from(["horizon", "pos", "vel", "id", "extra", "table", "pockets", "none"]),
        st.one_of(
            st.floats(allow_nan=True, allow_infinity=True),
            st.integers(-3, 3),
            st.text(max_size=3),
            st.booleans(),
            st.none(),
        ),
        st.integers(0, 6),
    )
    def check(field: str, value: object, ball: int) -> None:
        data = json.loads(json.dumps(base))
        if field == "horizon":
            data["horizon"] = value
        elif field in ("pos", "vel"):
            data["balls"][ball][field][ball % 2] = value
        elif field == "id":
            data["balls"][ball]["id"] = value
        elif field == "extra":
            data["balls"][ball]["spin"] = value
        elif field == "table":
            data["table"] = {"width": value, "height": 1.0}
        elif field == "pockets":
            data["pockets"]["radius"] = value
        text = json.dumps(data)
        light = light_scene(text)
        if light is None:
            return  # left to the ordinary path
        model = Scene.model_validate_json(text)  # never refused by the model
        assert light.scene_id == model.scene_id and light.horizon == model.horizon
        assert (light.table, light.physics, light.pockets) == (
            model.table,
            model.physics,
            model.pockets,
        )
        for a, b in zip(light.balls, model.balls, strict=True):
            assert (a.id, a.pos, a.vel) == (b.id, b.pos, b.vel)
            assert all(math.isfinite(c) for c in (*a.pos, *a.vel))

    check()
    assert light_scene(json.dumps(base)) is not None
    inside = json.loads(json.dumps(base))
    inside["balls"][2]["pos"] = [0.03, 0.03]
    assert light_scene(json.dumps(inside)) is None and light_scene(b"{") is None


def test_fast_lines_from_texts_equal_the_model_json() -> None:
    from bpb_tasks.billiards.truth_lines import text_lines

    scenes = [random_scene(22, i, speeds=(0.1, 6.0)) for i in range(50)]
    texts = [s.model_dump_json().encode() for s in scenes] + [b"not json"]
    lines = text_lines(texts, AnalyticSimulator(), None)
    assert lines is not None and lines[-1] is None
    python = AnalyticSimulator(engine="python")
    for line, s in zip(lines, scenes, strict=False):
        assert line is not None
        assert json.loads(line) == json.loads(final_state(s, python.run(s)).model_dump_json())


def test_a_short_job_does_not_load_the_kernel_and_a_long_one_does(tmp_path: Path) -> None:
    # loading numba and the cached kernels costs about a second: one scene is simulated in
    # Python, 300 go through the kernel; the lines are the same bytes either way
    files = []
    for i in range(300):
        files.append(tmp_path / f"scene_{i:03d}.json")
        files[-1].write_text(random_scene(22, i).model_dump_json())
    probe = (
        "import sys\nfrom pathlib import Path\nfrom bpb_core.simulate import simulate_lines\n"
        "paths = sorted(Path(sys.argv[1]).glob('*.json'))[: int(sys.argv[2])]\n"
        "lines = list(simulate_lines(paths, workers=1))\n"
        "print('numba' in sys.modules)\nprint('\\n'.join(lines))"
    )

    def run(count: int) -> tuple[bool, list[str]]:
        out = subprocess.run(
            [sys.executable, "-c", probe, str(tmp_path), str(count)],
            capture_output=True, text=True, check=True,
        ).stdout.splitlines()  # fmt: skip
        return out[0] == "True", out[1:]

    loaded_one, one = run(1)
    loaded_all, every = run(300)
    assert (loaded_one, loaded_all) == (False, True)
    assert one == every[:1] and len(every) == 300
