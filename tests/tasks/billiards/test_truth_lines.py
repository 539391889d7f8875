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
        st.sampled_from(
            ["horizon", "pos", "vel", "id", "extra", "table", "pockets", "none", "raw", "order"]
        ),
        st.one_of(
            st.floats(allow_nan=True, allow_infinity=True),
            st.integers(-3, 3),
            st.integers(2**31 - 2, 2**70),
            st.text(max_size=3),
            st.booleans(),
            st.none(),
            st.sampled_from(["1.0", "1e400", "-0", "1", "2.0e0"]),
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
        elif field == "order":
            data["balls"].reverse()  # ids out of order: sorted on the way to the kernel
        text = json.dumps(data)
        if field == "raw" and isinstance(value, str):  # a bare token, duplicated key
            text = text.replace('"horizon": ', f'"horizon": {value}, "horizon": ', 1)
            text = text.replace('"id": 2', f'"id": {value}', 1)
        light = light_scene(text)
        if light is None:
            return  # left to the ordinary path
        model = Scene.model_validate_json(text)  # never refused by the model
        assert light.scene_id == model.scene_id and light.horizon == model.horizon
        assert isinstance(light.horizon, float)
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


def test_rounding_on_arrays_is_pythons_round_bit_for_bit() -> None:
    import numpy as np
    from hypothesis import given, settings, strategies as st

    from bpb_tasks.billiards.truth_lines import round4

    ties = st.integers(-(10**8), 10**8).map(lambda m: (m + 0.5) / 1e4)  # near and at ties

    @settings(max_examples=300, deadline=None)
    @given(st.lists(st.one_of(st.floats(allow_nan=False), ties), min_size=1, max_size=50))
    def check(values: list[float]) -> None:
        got = round4(np.array(values, dtype=float))
        want = np.array([round(v, 4) + 0.0 for v in values])
        assert got.tobytes() == want.tobytes()  # signs of zero included

    check()


def test_texts_of_every_kind_give_the_model_bytes_or_are_left_to_it() -> None:
    # unsorted ids, other ball counts, another table, ids to escape, a bad text among them
    from bpb_tasks.billiards.scene import Scene
    from bpb_tasks.billiards.truth_lines import text_lines

    scenes = [random_scene(23, i, speeds=(0.1, 6.0)) for i in range(300)]
    texts = []
    for i, s in enumerate(scenes):
        data = json.loads(s.model_dump_json())
        if i % 5 == 2:
            data["balls"] = data["balls"][: 2 + i % 4]
        if i % 3 == 1:
            data["balls"].reverse()
        if i % 7 == 3:
            data["table"] = {"width": 2.5, "height": 1.25}
        if i % 11 == 4:
            data["scene_id"] = f'ü "quoted" \\ tab\t {i} \u0001 / 100%'
        if i % 13 == 5:  # the lines are templates filled with %: ids holding % stay as they are
            data["scene_id"] = f"100% {i} %s %(x)s %%"
        if i % 17 == 6:  # other ids than the group's others
            for k, ball in enumerate(data["balls"]):
                ball["id"] = 7 * k
        if i % 19 == 7:  # ids of every length up to the largest taken
            others = [ball for ball in data["balls"] if ball["id"] != 0]
            for k, ball in enumerate(others):
                ball["id"] = 2**31 - 1 - 10**k
        texts.append(json.dumps(data).encode())
    texts[10] = texts[10].replace(b'"horizon"', b'"horizon": 1, "x"')
    lines = text_lines(texts, AnalyticSimulator(), None)
    assert lines is not None and lines[10] is None
    python = AnalyticSimulator(engine="python")
    taken = 0
    for line, text in zip(lines, texts, strict=True):
        if line is None:
            continue
        model = Scene.model_validate_json(text)
        assert line == final_state(model, python.run(model)).model_dump_json()
        taken += 1
    assert taken == len(texts) - 1
    kept = "".join(line for line in lines if line is not None)  # the suite has every case
    assert '"pos":null' in kept and '"kind":"pocket"' in kept and '"kind":"ball"' in kept
    assert '"kind":"wall"' in kept and '"kind":"stop"' in kept and "%s %(x)s %%" in kept


def test_simulate_reads_large_files_and_restores_the_collector(tmp_path: Path) -> None:
    import gc

    from bpb_core.simulate import simulate_lines

    files = []
    for i in range(300):
        files.append(tmp_path / f"scene_{i:03d}.json")
        text = random_scene(24, i).model_dump_json()
        files[-1].write_text(text if i != 7 else text[:-1] + " " * 200_000 + "}")
    python = AnalyticSimulator(engine="python")
    want = [final_state(s, python.run(s)).model_dump_json()
            for s in (random_scene(24, i) for i in range(300))]  # fmt: skip
    for enabled in (True, False):
        (gc.enable if enabled else gc.disable)()
        try:
            assert list(simulate_lines(files, workers=1)) == want
            assert gc.isenabled() is enabled
        finally:
            gc.enable()


def test_a_scene_file_that_is_not_utf8_is_named_after_the_lines_before_it(tmp_path: Path) -> None:
    # msgspec raises UnicodeDecodeError, not one of its own errors, for such a text
    from bpb_core.errors import BadInput
    from bpb_core.simulate import simulate_lines

    files = []
    for i in range(300):
        text = random_scene(25, i).model_dump_json().encode()
        if i == 150:
            text = text.replace(b'"scene_id":"', b'"scene_id":"\xc3 ', 1)
        files.append(tmp_path / f"scene_{i:03d}.json")
        files[-1].write_bytes(text)
    lines = []
    with pytest.raises(BadInput, match=r"scene_150\.json: Invalid JSON"):
        for line in simulate_lines(files, workers=1):
            lines.append(line)
    assert len(lines) == 150
