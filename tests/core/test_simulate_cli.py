"""``bpb simulate`` through the CLI's entry point (in this process, unless a process is what is
under test: standard input and output, signals, installed plugins): output order, formats,
overrides, bad input."""

from __future__ import annotations

import contextlib
import io
import json
import os
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import pytest

import support.flawed_family
from bpb_core import SimulatorInfo, hookimpl
from bpb_core.dataset import generate_dataset
from bpb_core.registry import PluginSource, make_registry
from bpb_core.simulate import simulate_lines
from bpb_tasks.billiards.bench_compare import random_scene
from bpb_tasks.billiards.scene.model import DEFAULT_RADIUS, Scene, table_box
from bpb_tasks.billiards.truth.final import FinalState, final_state
from bpb_tasks.simulators.analytic import AnalyticSimulator
from support.processes import HAS_PROC, as_in_a_terminal, ctrl_c, ctrl_c_at_worker_start

BPB = str(Path(sys.executable).with_name("bpb"))


def bpb(*args: str) -> subprocess.CompletedProcess[str]:
    """``bpb *args`` run in this process: its exit code and what it printed."""
    from bpb_core.cli.main import main

    out, err, code = io.StringIO(), io.StringIO(), 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main(list(args))
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 0
    return subprocess.CompletedProcess(args, code, out.getvalue(), err.getvalue())


def bpb_process(*args: str, **kwargs: Any) -> subprocess.CompletedProcess[str]:
    return subprocess.run([BPB, *args], capture_output=True, text=True, timeout=120, **kwargs)


def write(path: Path, scene: Scene) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(scene.model_dump_json(indent=2))
    return path


@pytest.fixture
def scenes(tmp_path: Path) -> list[tuple[Path, Scene]]:
    out = []
    for i in range(3):
        s = random_scene(11, i)
        out.append((write(tmp_path / f"s{i}.json", s), s))
    return out


def lines(result: subprocess.CompletedProcess[str]) -> list[FinalState]:
    assert result.returncode == 0, result.stderr
    return [FinalState.model_validate_json(line) for line in result.stdout.splitlines()]


def test_one_line_per_scene_in_input_order(scenes: list[tuple[Path, Scene]]) -> None:
    order = [scenes[2], scenes[0], scenes[1]]
    finals = lines(bpb("simulate", *(str(p) for p, _ in order)))
    assert [f.scene_id for f in finals] == [s.scene_id for _, s in order]
    sim = AnalyticSimulator()
    for final, (_, s) in zip(finals, order, strict=True):
        assert final == final_state(s, sim.run(s))


def test_dataset_folder_and_final_json(tmp_path: Path) -> None:
    root = tmp_path / "data"
    for horizon, index in ((2, 1), (1, 0), (2, 0)):
        s = random_scene(5, index).model_copy(update={"scene_id": f"h{horizon}_{index:04d}"})
        write(root / f"h{horizon}" / f"scene_{index:04d}" / "init.json", s)
    (root / "h2" / "scene_0000" / "final.json").write_text("{}")
    finals = lines(bpb("simulate", str(root)))
    assert [f.scene_id for f in finals] == ["h1_0000", "h2_0000", "h2_0001"]
    again = lines(bpb("simulate", str(root / "h2" / "scene_0000" / "final.json")))
    assert [f.scene_id for f in again] == ["h2_0000"]


def test_horizon_override_and_stability(scenes: list[tuple[Path, Scene]]) -> None:
    path, scene = scenes[0]
    (final,) = lines(bpb("simulate", str(path), "--horizon", "0.25", "--stability"))
    assert final.horizon == 0.25
    assert final == final_state(scene, AnalyticSimulator().run(scene, 0.25)).model_copy(
        update={"stability": final.stability}
    )
    assert final.stability is not None and final.stability.delta == 1e-4


def test_stability_of_a_scene_whose_second_past_the_horizon_crosses_the_event_cap(
    tmp_path: Path,
) -> None:
    """A ball bouncing between two cushions 14 um further apart than its diameter: 70,729
    events to its horizon of 1 s, within the analytic engine's cap of 100,000, while the
    horizon gap's run to 1 s past the horizon is not. `bpb simulate --stability` failed on it
    (exit 2, 'more than 100000 events before t=2.0') where `bpb simulate` succeeds; that run
    now stops at the cap, and the first event after the horizon, which came before it, gives
    the uncapped gap."""
    pytest.importorskip("numba")  # the pure-Python engine takes about 100 s for it
    from bpb_tasks.billiards.stability.annotation import kernel_horizon_gap

    radius, gap = 0.028575, 1.4e-5
    narrow = Scene.model_validate(
        {
            "scene_id": "narrow",
            "horizon": 1.0,
            "table": {"width": 2.0, "height": 2 * radius + gap},
            "pockets": {"radius": 0.06, "centers": []},
            "balls": [{"id": 0, "pos": [0.5, radius + gap / 2], "vel": [0.0, 1.0]}],
        }
    )
    path = write(tmp_path / "narrow.json", narrow)
    (final,) = lines(bpb("simulate", str(path), "--stability"))
    assert 90_000 > len(final.events) > 50_000
    assert final.stability is not None and final.stability.horizon_gap is not None
    assert final.stability.horizon_gap == kernel_horizon_gap(narrow, 1.0, 10**6)


def test_pymunk_stability_of_a_scene_whose_second_past_the_horizon_is_over_the_step_budget(
    tmp_path: Path,
) -> None:
    """A ball against the right cushion rolling into it at 1 cm/s, stopped by friction within
    1 ms. At --dt 9e-8 its 0.5 s horizon is within pymunk's budget of 10,000,000 steps, the
    horizon gap's run to 1.5 s is not (the budget allows for balls moving until a second after
    they surely rest): `bpb simulate --stability` exited 2 ('1.11e+07 steps of 9e-08 s to
    reach t=1.5') where `bpb simulate` succeeds. That run now stops where the budget would
    have refused it; the ball rested long before, so the gap is the exact one."""
    radius = DEFAULT_RADIUS
    touching = Scene.model_validate(
        {
            "scene_id": "touching",
            "horizon": 0.5,
            "physics": {"mu": 1.0},
            "pockets": {"radius": 0.06, "centers": []},
            "balls": [{"id": 0, "pos": [2.0 - radius, 0.5], "vel": [0.01, 0.0]}],
        }
    )
    path = write(tmp_path / "touching.json", touching)
    args = ("simulate", str(path), "--simulator", "pymunk", "--dt", "9e-8")
    (plain,) = lines(bpb(*args))
    (final,) = lines(bpb(*args, "--stability"))
    assert final.events == plain.events and [e.kind for e in final.events] == ["wall", "stop"]
    assert final.stability is not None and final.stability.horizon_gap == 0.5 - 9e-8


def test_pymunk_with_dt(scenes: list[tuple[Path, Scene]]) -> None:
    path, scene = scenes[1]
    (final,) = lines(bpb("simulate", str(path), "--simulator", "pymunk", "--dt", "0.01"))
    assert final.simulator == "pymunk" and final.scene_id == scene.scene_id


def test_pymunk_refuses_a_step_that_tunnels_and_the_bound_it_names_works(
    scenes: list[tuple[Path, Scene]],
) -> None:
    # --dt 0.1 carried this cue ball through the bottom cushion to (0.61, -1.43), written as
    # its truth with exit 0
    path, scene = scenes[0]
    message = one_line_error(bpb("simulate", str(path), "--simulator", "pymunk", "--dt", "0.1"))
    said = f"error: {path}: --dt: 0.1 s is above this scene's stability bound, "
    assert message.startswith(said) and message.endswith("can carry a ball through a cushion")
    bound = message[len(said) :].split(" s ", 1)[0]
    (final,) = lines(bpb("simulate", str(path), "--simulator", "pymunk", "--dt", bound))
    lo_x, hi_x, lo_y, hi_y = table_box(scene.table, scene.physics.ball_radius)
    on_table = [p.pos for p in final.predictions if p.pos is not None]
    assert on_table and all(lo_x <= x <= hi_x and lo_y <= y <= hi_y for x, y in on_table)


def one_line_error(result: subprocess.CompletedProcess[str]) -> str:
    assert result.returncode == 2, result.stderr
    assert result.stdout == ""
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    return result.stderr.strip()


def test_bad_scene_names_file_and_field(tmp_path: Path) -> None:
    data = json.loads(random_scene(1, 0).model_dump_json())
    data["balls"][2]["pos"] = [2.5, 0.4]
    bad = tmp_path / "scenes" / "x.json"
    bad.parent.mkdir()
    bad.write_text(json.dumps(data))
    message = one_line_error(bpb("simulate", str(bad)))
    assert f"{bad}: balls[2].pos:" in message and "off the table" in message


def test_resting_ball_inside_a_pocket_circle_is_bad_input(tmp_path: Path) -> None:
    data = json.loads(random_scene(1, 0).model_dump_json())
    data["balls"][3].update(pos=[0.03, 0.03], vel=[0.0, 0.0])  # pocket 0 is the corner (0, 0)
    bad = tmp_path / "init.json"
    bad.write_text(json.dumps(data))
    message = one_line_error(bpb("simulate", str(bad)))
    assert f"{bad}: balls[3].pos: ball 3 at [0.03, 0.03] starts inside pocket 0" in message


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        ("{not json", "Invalid JSON"),
        (
            '{"scene_id": "a", "horizon": 1, "balls": [{"id": 0, "pos": ["a", 0.5]}]}',
            "balls[0].pos[0]",
        ),
        ('{"scene_id": "a", "horizon": 0, "balls": [{"id": 0, "pos": [0.5, 0.5]}]}', "horizon:"),
    ],
)
def test_malformed_files_are_one_line_errors(tmp_path: Path, content: str, expected: str) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text(content)
    message = one_line_error(bpb("simulate", str(bad)))
    assert str(bad) in message and expected in message


def test_missing_path_and_unknown_simulator(
    scenes: list[tuple[Path, Scene]], tmp_path: Path
) -> None:
    assert "no such file" in one_line_error(bpb("simulate", str(tmp_path / "nope.json")))
    message = one_line_error(bpb("simulate", str(scenes[0][0]), "--simulator", "nosuch"))
    assert "analytic" in message and "pymunk" in message
    assert "--dt" in one_line_error(bpb("simulate", str(scenes[0][0]), "--dt", "0.01"))
    assert "--precision" in one_line_error(bpb("simulate", str(scenes[0][0]), "--precision", "x"))


FLAWED = "plugin 'flawed' (flawed_family) from bpb-flawed 1.2"


@pytest.fixture
def flawed_data(install: Any, tmp_path: Path) -> Path:
    """The ``flawed`` scene family (billiards renamed, with its simulator ``flawed-analytic``;
    its config names ``analytic``) installed for ``run_bpb``, and two scenes it made."""
    source = Path(support.flawed_family.__file__).read_text()
    install("bpb-flawed", "1.2", {"flawed_family": source}, {"flawed": "flawed_family"})
    plugin = PluginSource("flawed", "bpb-flawed", "1.2", "flawed_family")
    registry = make_registry([(support.flawed_family, plugin)])
    return generate_dataset(tmp_path / "flawed", 2, (1.0,), 0, family="flawed", workers=1,
                            images=False, registry=registry)  # fmt: skip


def test_a_simulator_of_another_family_than_the_dataset_s_is_one_line(
    run_bpb: Any, flawed_data: Path, small_dataset: Path
) -> None:
    """The simulator's family used to read the dataset's scenes, whatever family made them
    (for unlike families: errors about fields of their scene files)."""
    done = run_bpb("simulate", str(small_dataset), "--simulator", "flawed-analytic")
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"error: --simulator flawed-analytic: simulates flawed scenes, but {small_dataset} holds "
        "billiards scenes"
    ]
    assert done.stdout == ""
    done = run_bpb("simulate", str(flawed_data), "--simulator", "pymunk")
    assert done.returncode == 2 and done.stderr.strip().splitlines() == [
        f"error: --simulator pymunk: simulates billiards scenes, but {flawed_data} holds flawed "
        "scenes"
    ]


def test_the_simulator_a_dataset_s_config_names_simulates_with_the_dataset_s_family(
    run_bpb: Any, flawed_data: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Generation paired the flawed family with analytic (a billiards simulator): that pairing
    is taken, and the scenes are read and simulated by the dataset's family, as generated
    (a ground_truths() one short shows which family ran)."""
    done = run_bpb("simulate", str(flawed_data), "--simulator", "analytic")
    assert done.returncode == 0, done.stderr
    assert [json.loads(line)["scene_id"] for line in done.stdout.splitlines()] == [
        "h1_0000",
        "h1_0001",
    ]
    monkeypatch.setenv("BPB_TEST_FLAW", "ground_truths_short")
    many = [str(flawed_data)] * 128  # 256 scenes: in batches
    done = run_bpb("simulate", *many, "--simulator", "analytic", "--workers", "1")
    assert done.returncode == 3
    assert done.stderr.startswith(f"error: {FLAWED}: scene family 'flawed': ground_truths() ")


@pytest.mark.parametrize(
    ("args", "count", "bad"),
    [([], 300, 20), (["--workers", "2"], 300, 200), (["--stability"], 40, 20)],
    ids=["batch", "forked", "ordinary"],
)
def test_an_event_cap_overrun_among_many_scenes_is_named_never_truncated(
    tmp_path: Path, args: list[str], count: int, bad: int
) -> None:
    # a frictionless ball between two cushions never rests: its truth is never a cut-off run
    paths = [write(tmp_path / f"s{i:03d}.json", random_scene(11, i)) for i in range(count)]
    endless = random_scene(11, bad).model_dump(mode="json")
    endless.update(horizon=1e9, physics={"mu": 0.0}, pockets={"radius": 0.0, "centers": []})
    endless["balls"] = [{"id": 0, "pos": [0.5, 0.5], "vel": [0.0, 1.0]}]
    paths[bad].write_text(json.dumps(endless))
    done = bpb("simulate", *map(str, paths), *args)
    assert one_line_error_after_output(done) == (
        f"error: {paths[bad]}: more than 100000 events before t=1000000000.0"
    )
    kept = [FinalState.model_validate_json(line).scene_id for line in done.stdout.splitlines()]
    assert kept == [f"r11_{i:05d}" for i in range(bad)]  # those before it, none after


def one_line_error_after_output(result: subprocess.CompletedProcess[str]) -> str:
    assert result.returncode == 2, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    return result.stderr.strip()


def test_mpmath_precision_matches_float64(scenes: list[tuple[Path, Scene]]) -> None:
    paths = [str(p) for p, _ in scenes]
    exact = lines(bpb("simulate", *paths, "--precision", "40"))
    fast = lines(bpb("simulate", *paths))
    assert [f.q1 for f in exact] == [f.q1 for f in fast]
    assert [f.predictions for f in exact] == [f.predictions for f in fast]


def test_lines_before_a_bad_file_are_kept(scenes: list[tuple[Path, Scene]], tmp_path: Path) -> None:
    bad = tmp_path / "broken.json"
    bad.write_text("[]")
    result = bpb("simulate", str(scenes[0][0]), str(scenes[1][0]), str(bad), str(scenes[2][0]))
    assert result.returncode == 2
    assert len(result.stdout.splitlines()) == 2
    assert str(bad) in result.stderr and len(result.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("args", [[], ["--simulator", "pymunk"]])
def test_a_scene_piped_on_stdin_is_read_once(
    scenes: list[tuple[Path, Scene]], args: list[str]
) -> None:
    # `cat init.json | bpb simulate /dev/stdin`: the pipe was read by the fast path, then
    # opened again by the ordinary path and found empty ("Invalid JSON: EOF")
    path, scene = scenes[0]
    piped = bpb_process("simulate", str(scenes[1][0]), "/dev/stdin", *args,
                        input=path.read_text())  # fmt: skip
    files = lines(bpb("simulate", str(scenes[1][0]), str(path), *args))
    assert lines(piped) == files and files[1].scene_id == scene.scene_id
    bad = json.loads(path.read_text())
    bad["balls"][0]["vel"] = [1000.0, 0.0]
    refused = bpb_process("simulate", "/dev/stdin", *args, input=json.dumps(bad))
    assert refused.returncode == 2
    assert refused.stderr.strip().splitlines() == [
        "error: /dev/stdin: balls[0].vel: speed 1000 m/s is above 100 m/s"
    ]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_a_named_pipe_is_simulated_not_waited_on(
    scenes: list[tuple[Path, Scene]], tmp_path: Path
) -> None:
    fifo = tmp_path / "scene.fifo"
    os.mkfifo(fifo)
    path, scene = scenes[0]

    def write() -> None:
        with open(fifo, "w", encoding="utf-8") as pipe:
            pipe.write(path.read_text())

    writer = threading.Thread(target=write, daemon=True)
    writer.start()
    try:
        result = bpb_process("simulate", str(fifo))  # the timeout bounds a hang
    except subprocess.TimeoutExpired:
        pytest.fail("bpb simulate waited for a second writer on the named pipe")
    writer.join()
    (final,) = lines(result)
    assert final == final_state(scene, AnalyticSimulator().run(scene))


@pytest.mark.skipif(not HAS_PROC, reason="lists children through /proc")
def test_ctrl_c_reaching_the_workers_is_left_to_the_parent(small_dataset: Path) -> None:
    """bpb simulate's forked workers printed a traceback each when Ctrl-C reached them."""
    import time

    args = [BPB, "simulate", *[str(small_dataset)] * 400, "--stability", "--workers", "2"]
    process = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True, start_new_session=True,
                               preexec_fn=as_in_a_terminal)  # fmt: skip
    stderr = ctrl_c(process, 2, time.monotonic() + 60)
    assert process.returncode == 130, stderr
    assert stderr.strip() == "aborted"


def test_a_ctrl_c_while_the_workers_start_is_aborted_without_a_traceback(
    small_dataset: Path, tmp_path: Path
) -> None:
    """A worker that Ctrl-C reached before its pool initializer died of it with a traceback."""
    args = [BPB, "simulate", *[str(small_dataset)] * 400, "--stability", "--workers", "2"]
    code, stderr = ctrl_c_at_worker_start(args, 2, tmp_path)
    assert (code, stderr.strip()) == (130, "aborted")


class FreeSimulator:
    """A plugin's simulator registered for no family: any dataset may pair with it."""

    @hookimpl
    def bpb_simulators(self) -> list[SimulatorInfo]:
        return [SimulatorInfo("free", lambda: AnalyticSimulator, "Analytic, for any family")]


def test_a_simulator_registered_for_no_family_simulates_any_dataset(
    flawed_data: Path, small_dataset: Path
) -> None:
    registry = make_registry([support.flawed_family, FreeSimulator()])
    for data in (small_dataset, flawed_data):
        finals = list(simulate_lines([data], simulator="free", workers=1, registry=registry))
        ids = {json.loads(line)["scene_id"] for line in finals}
        assert len(ids) == len(finals) == len(list(data.glob("h*/scene_*/init.json")))


LABELLED = '''
import json
from pathlib import Path

from bpb_core import SimulatorInfo, hookimpl
from bpb_core.errors import BadInput
from bpb_tasks.simulators.analytic.engine import AnalyticSimulator


class Labelled(AnalyticSimulator):
    """Analytic, under a label: its options are called name and names."""

    def __init__(self, name: str = "", names: str = "", record: str = "") -> None:
        if not name:
            raise BadInput.about("name", "must not be empty")
        super().__init__()
        Path(record).write_text(json.dumps({"name": name, "names": names}))


@hookimpl
def bpb_simulators() -> list[SimulatorInfo]:
    return [SimulatorInfo("labelled", lambda: Labelled, "Analytic, labelled", family="billiards")]
'''


def test_a_plugin_simulator_may_take_options_called_name_and_names(
    install: Any, run_bpb: Any, scenes: list[tuple[Path, Scene]], tmp_path: Path
) -> None:
    """The registry's own parameters were called name and names, so a simulator taking options
    of those names could not be built (Python: got multiple values for argument 'name')."""
    install("bpb-labelled", "0.1", {"labelled_sim": LABELLED}, {"labelled": "labelled_sim"})
    path, scene = scenes[0]
    record = tmp_path / "record.json"
    spec = f"labelled:name=cue,names=left|right,record={record}"
    done = run_bpb("simulate", str(path), "--simulator", spec)
    assert done.returncode == 0, done.stderr
    assert json.loads(record.read_text()) == {"name": "cue", "names": "left|right"}
    (final,) = lines(done)
    assert final == final_state(scene, AnalyticSimulator().run(scene))
    refused = run_bpb("simulate", str(path), "--simulator", "labelled:name=,names=x")
    assert refused.returncode == 2
    assert refused.stderr.strip().splitlines() == [
        "error: --simulator 'labelled:name=,names=x': name: must not be empty"
    ]


@pytest.mark.parametrize("encoding", ["utf-8", "latin-1"])
def test_lines_are_printed_in_the_encoding_of_standard_output(
    tmp_path: Path, encoding: str
) -> None:
    paths = []
    for i in range(300):  # past BATCH_MIN: in batches
        scene = random_scene(31, i)
        if i % 7 == 3:
            scene = scene.model_copy(update={"scene_id": f"schön {i}"})
        paths.append(write(tmp_path / f"s{i:03d}.json", scene))
    expected = list(simulate_lines(paths, workers=1))
    env = {**os.environ, "PYTHONIOENCODING": encoding}
    done = subprocess.run([BPB, "simulate", *map(str, paths)], capture_output=True, env=env,
                          timeout=120, check=True)  # fmt: skip
    assert done.stdout == "".join(f"{line}\n" for line in expected).encode(encoding)
    assert any("schön" in line for line in expected)


def test_a_caller_that_captures_standard_output_in_a_string_gets_the_lines(
    scenes: list[tuple[Path, Scene]],
) -> None:
    """``io.StringIO`` has no file and no encoding (None): the lines go to it as text (an
    internal error before, looking the encoding None up)."""
    import contextlib
    import io

    from bpb_core.cli.main import main

    paths = [str(p) for p, _ in scenes]
    captured = io.StringIO()
    with contextlib.redirect_stdout(captured), pytest.raises(SystemExit) as ended:
        main(["simulate", "--workers", "1", *paths])
    assert ended.value.code in (0, None)
    assert captured.getvalue() == "".join(f"{line}\n" for line in simulate_lines(paths, workers=1))


def test_paths_from_a_file_and_from_standard_input(
    scenes: list[tuple[Path, Scene]], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Long path lists come from --from-file FILE (or -) and from '-' among the arguments, one
    path a line, in the order given: arguments first, each '-' where it stands."""
    (a, _), (b, _), (c, _) = scenes
    listed = tmp_path / "paths.txt"
    listed.write_text(f"{b}\n\n{c}\r\n")
    want = lines(bpb("simulate", str(a), str(b), str(c)))
    assert lines(bpb("simulate", str(a), "--from-file", str(listed))) == want
    monkeypatch.setattr("sys.stdin", io.StringIO(f"{b}\n{c}\n"))
    assert lines(bpb("simulate", str(a), "-")) == want
    monkeypatch.setattr("sys.stdin", io.StringIO(f"{a}\n{b}\n"))
    assert lines(bpb("simulate", "--from-file", "-", str(c))) == lines(
        bpb("simulate", str(c), str(a), str(b))
    )
    missing = tmp_path / "none.txt"
    assert one_line_error(bpb("simulate", "--from-file", str(missing))) == (
        f"error: --from-file {missing}: cannot read: No such file or directory"
    )
    monkeypatch.setattr("sys.stdin", io.StringIO(""))
    assert one_line_error(bpb("simulate", "-")) == (
        "error: no scene paths given (arguments, --from-file FILE, or - for stdin)"
    )
    assert one_line_error(bpb("simulate")).startswith("error: no scene paths given")


def test_a_reader_that_leaves_early_ends_it_quietly(small_dataset: Path) -> None:
    """``bpb simulate ... | head -1``: the closed pipe was an internal error (exit 1 or 3)."""
    args = [BPB, "simulate", *[str(small_dataset)] * 60]  # 360 lines, past a pipe's buffer
    process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert process.stdout is not None and process.stderr is not None
    first = process.stdout.readline()
    process.stdout.close()
    stderr = process.stderr.read()
    assert process.wait(timeout=120) == 141
    assert json.loads(first)["scene_id"] == "h1_0000" and stderr == b""
