"""``bpb generate`` with the ``pymunk`` simulator: its options (``dt``) are set in the config's
``simulator`` as ``bpb bench sim`` takes contestants, recorded in the manifest, and used again by
``bpb simulate``; a step too long for a scene is refused naming where to set it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

BPB = str(Path(sys.executable).with_name("bpb"))
# cues at 15-20 m/s: pymunk's default step (1e-3 s) is above the stability bound of each scene
# (half the ball radius over the cue speed: 0.00095 s at 15 m/s), 0.0005 s is below all of them
FAST = {"balls": 3, "speed_ranges": {"1": {"low": 15, "high": 20}}}


def _generate(config: Path, out: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [BPB, "generate", "--out", str(out), "--config", str(config), "--horizons", "1",
         "--per-horizon", "3", "--seed", "4", "--workers", "1", "--no-images"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip


def _config(folder: Path, simulator: str) -> Path:
    path = folder / f"{simulator.replace(':', '_')}.json"
    path.write_text(json.dumps({"simulator": simulator, **FAST}))
    return path


def test_a_step_too_long_names_the_config_s_simulator_not_a_flag(tmp_path: Path) -> None:
    # it said "--dt: 0.001 s is above ...", a flag bpb generate does not have, with no way to
    # set pymunk's step for generation
    config = _config(tmp_path, "pymunk")
    done = _generate(config, tmp_path / "ds")
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and "--dt" not in done.stderr
    assert done.stderr.startswith(
        f"error: {config}: scene h1_0000: dt: 0.001 s is above this scene's stability bound, "
    )
    assert done.stderr.endswith(
        "; the simulator cannot finish it: set dt in the config's simulator 'pymunk' "
        "(pymunk:dt=...)\n"
    )
    assert not (tmp_path / "ds").exists()


def test_a_step_over_pymunk_s_budget_names_the_config_s_simulator(tmp_path: Path) -> None:
    # it was the bare "pymunk: 2e+07 steps of 1e-07 s to reach t=2 ...; use a shorter horizon
    # or a larger dt", naming neither the config file nor the scene nor where dt is set
    config = tmp_path / "small_dt.json"
    config.write_text(json.dumps({"simulator": "pymunk:dt=1e-7"}))
    done = subprocess.run(
        [BPB, "generate", "--out", str(tmp_path / "ds"), "--config", str(config),
         "--horizons", "2", "--per-horizon", "1", "--workers", "1", "--no-images"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr == (
        f"error: {config}: scene h2_0000: dt: 2e+07 steps of 1e-07 s to reach t=2 with balls "
        "still moving (at most 10,000,000); use a shorter horizon or a larger dt; the simulator "
        "cannot finish it: set dt in the config's simulator 'pymunk:dt=1e-7' (pymunk:dt=...)\n"
    )
    assert not (tmp_path / "ds").exists()


def test_a_step_set_in_the_config_makes_a_recorded_reproducible_dataset(tmp_path: Path) -> None:
    config = _config(tmp_path, "pymunk:dt=0.0005")
    first, again = tmp_path / "first", tmp_path / "again"
    for out in (first, again):
        done = _generate(config, out)
        assert done.returncode == 0, done.stderr
    # the same seed twice: byte-identical files
    checksums = (first / "checksums.sha256").read_bytes()
    assert checksums == (again / "checksums.sha256").read_bytes()
    assert checksums.count(b"final.json") == 3
    # the manifest records the step with the rest of the config; final.json the simulator
    manifest = json.loads((first / "dataset.json").read_text())
    assert manifest["config"]["simulator"] == "pymunk:dt=0.0005"
    finals = [json.loads(p.read_text()) for p in sorted(first.glob("h1/*/final.json"))]
    assert [f["simulator"] for f in finals] == ["pymunk"] * 3
    # bpb simulate runs the dataset's simulator with its recorded step: the same truth
    done = subprocess.run([BPB, "simulate", str(first), "--stability"], capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert [json.loads(line) for line in done.stdout.splitlines()] == finals
    # a simulator chosen by flag is built from the flags, whose --dt it names
    done = subprocess.run([BPB, "simulate", str(first), "--simulator", "pymunk"],
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 2 and ": --dt: 0.001 s is above this scene's" in done.stderr
    # --simulator takes the spec a config takes (it was "unknown simulator 'pymunk:dt=0.0005'"):
    # the same truth; a step in it that is too long is named there; --dt wins over it
    done = subprocess.run([BPB, "simulate", str(first), "--simulator", "pymunk:dt=0.0005"],
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert [json.loads(line) for line in done.stdout.splitlines()] == [
        {**final, "stability": None} for final in finals
    ]
    done = subprocess.run([BPB, "simulate", str(first), "--simulator", "pymunk:dt=0.001"],
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 2
    assert ": --simulator 'pymunk:dt=0.001': dt: 0.001 s is above this scene's" in done.stderr
    flags = ["--simulator", "pymunk:dt=0.001", "--dt", "0.0005"]
    done = subprocess.run([BPB, "simulate", str(first), *flags], capture_output=True, text=True,
                          timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr


def test_the_oracle_runs_the_dataset_s_simulator_with_its_options(tmp_path: Path) -> None:
    # the oracle looked the config's simulator up as a bare name: "pymunk:dt=0.0005" is none
    from bpb_core.dataset import generate_dataset
    from bpb_core.results import load_results
    from bpb_core.results.tables import leaderboard
    from bpb_core.runner import run_eval
    from bpb_core.runner.options import RunOptions

    config = {**FAST, "simulator": "pymunk:dt=0.0005"}
    data = generate_dataset(tmp_path / "data", 3, [1.0], seed=2, config=config, workers=1,
                            images=False)  # fmt: skip
    run_eval(data, "baseline:oracle", tmp_path / "runs" / "oracle", RunOptions(input_mode="state"))
    results = load_results(tmp_path / "runs")
    board = leaderboard(results.units, results.suites).set_index("run")
    assert board.loc["oracle", ["q1", "q2", "q3", "total"]].tolist() == [1.0] * 4
