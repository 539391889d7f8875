"""``bpb generate`` through the real entry point."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from support.paths import tree
from support.processes import (
    HAS_PROC,
    as_in_a_terminal,
    catches_sigterm,
    ctrl_c,
    ctrl_c_at_worker_start,
    settled_workers,
)

BPB = str(Path(sys.executable).with_name("bpb"))


def bpb(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([BPB, *args], capture_output=True, text=True, timeout=120)


def test_generate_writes_a_dataset_and_prints_realised_rates(tmp_path: Path) -> None:
    out = tmp_path / "ds"
    done = bpb("generate", "--out", str(out), "--per-horizon", "4", "--horizons", "2,4",
               "--seed", "3", "--workers", "2", "--no-images")  # fmt: skip
    assert done.returncode == 0, done.stderr
    manifest = json.loads((out / "dataset.json").read_text())
    assert manifest["scenes"] == 8 and manifest["horizons"] == [2.0, 4.0]
    for label in ("h2", "h4"):
        rate = manifest["summary"][label]["collision_rate"]
        assert f"{rate:.1%}" in done.stdout


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--horizons", "1,x"], "--horizons: 'x' is not a number"),
        (["--horizons", "1,-2"], "--horizons: '-2' must be a positive"),
        (["--per-horizon", "0"], "--per-horizon: must be at least 1"),
        (["--workers", "0"], "--workers: must be at least 1"),
        (["--horizons", "7"], "config: speed_ranges: no cue-speed range for horizon 7 s"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(tmp_path: Path, args: list[str], expected: str) -> None:
    done = bpb("generate", "--out", str(tmp_path / "ds"), *args)
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and expected in done.stderr
    assert not (tmp_path / "ds").exists()


def test_bad_config_exits_2_naming_the_file_and_field(tmp_path: Path) -> None:
    config = tmp_path / "cfg.toml"
    config.write_text("[physics]\nball_radius = -0.1\n")
    done = bpb("generate", "--out", str(tmp_path / "ds"), "--config", str(config))
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and f"{config}: physics.ball_radius:" in lines[0]


def test_existing_folder_is_refused_unless_overwrite(tmp_path: Path) -> None:
    out = tmp_path / "ds"
    common = ["generate", "--out", str(out), "--per-horizon", "1", "--horizons", "1",
              "--workers", "1", "--no-images"]  # fmt: skip
    assert bpb(*common).returncode == 0
    again = bpb(*common)
    assert again.returncode == 2 and "pass overwrite=True (--overwrite)" in again.stderr
    assert bpb(*common, "--overwrite").returncode == 0


def test_a_config_that_cannot_be_sampled_exits_2(tmp_path: Path) -> None:
    config = tmp_path / "crowded.json"
    config.write_text('{"balls": 16, "physics": {"ball_radius": 0.2}}')
    done = bpb("generate", "--out", str(tmp_path / "ds"), "--config", str(config),
               "--per-horizon", "1", "--horizons", "1", "--no-images")  # fmt: skip
    assert done.returncode == 2
    assert f"{config}: balls: could not place ball" in done.stderr
    assert done.stderr.strip().count("\n") == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["crowded.json"]  # no half-built folder


def test_a_horizon_calibration_cannot_serve_exits_2_and_keeps_the_old_dataset(
    tmp_path: Path,
) -> None:
    """The family's own --calibrate refusals name the config file that asks for them, as the
    simulator's refusal of a calibration draw does; they started "--calibrate: horizon ..."."""
    out = tmp_path / "ds"
    common = ["generate", "--out", str(out), "--per-horizon", "1", "--workers", "1",
              "--no-images"]  # fmt: skip
    assert bpb(*common, "--horizons", "1").returncode == 0
    before = (out / "dataset.json").read_bytes()
    config = tmp_path / "quick.json"
    config.write_text('{"calibration": {"samples": 20, "iterations": 4}}')
    done = bpb(*common, "--horizons", "0.001", "--calibrate", "--config", str(config),
               "--overwrite")  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"error: {config}: --calibrate: horizon 0.001 s: the cue ball hits another ball in only "
        "0.0% of calibration scenes even at 64 m/s, below the calibration.target 0.5; choose "
        "a longer horizon or a lower target"
    ]
    assert (out / "dataset.json").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds", "quick.json"]
    # no friction, no pockets, a day-long horizon: the first calibration scenes never end
    config.write_text(
        '{"physics": {"mu": 0}, "pockets": {"radius": 0}, '
        '"calibration": {"samples": 20, "iterations": 4}}'
    )
    done = bpb(*common, "--horizons", "100000", "--calibrate", "--config", str(config),
               "--overwrite")  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"error: {config}: --calibrate: horizon 100000 s: a calibration scene needs more "
        "than 100,000 events at cue speeds up to 0.5 m/s; choose a shorter horizon"
    ]
    assert (out / "dataset.json").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds", "quick.json"]


def test_stable_only_that_finds_too_few_stable_scenes_exits_2_and_writes_nothing(
    tmp_path: Path,
) -> None:
    config = tmp_path / "shaky.json"  # 5 cm perturbations: (almost) no scene is stable
    config.write_text('{"stability_delta": 0.05, "stability_samples": 8}')
    done = bpb("generate", "--out", str(tmp_path / "ds"), "--config", str(config), "--stable-only",
               "--per-horizon", "2", "--horizons", "3", "--no-images")  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().count("\n") == 0
    assert "--stable-only: horizon 3 s: only 0 of" in done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["shaky.json"]


@pytest.mark.skipif(not HAS_PROC, reason="lists children through /proc")
def test_a_ctrl_c_reaching_the_workers_is_left_to_the_parent(tmp_path: Path) -> None:
    import time

    out = tmp_path / "ds"
    args = [BPB, "generate", "--out", str(out), "--per-horizon", "30", "--workers", "2"]
    process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True, preexec_fn=as_in_a_terminal)  # fmt: skip
    try:
        for pid in settled_workers(process.pid, 2, time.monotonic() + 120):
            os.kill(pid, signal.SIGINT)  # what a terminal's Ctrl-C sends them
        _, stderr = process.communicate(timeout=120)  # a worker killed mid-scene hung it
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)  # do not leave it and its pool behind
    assert process.returncode == 0 and "Traceback" not in stderr, stderr
    assert json.loads((out / "dataset.json").read_text())["scenes"] == 150


def test_a_ctrl_c_while_the_workers_start_is_aborted_without_a_traceback(tmp_path: Path) -> None:
    """A worker that Ctrl-C reached after its fork but before its pool initializer (which
    ignores it) died of it with a traceback ("Process ForkPoolWorker-1: ... KeyboardInterrupt")."""
    for attempt in range(2):
        scratch = tmp_path / str(attempt)
        scratch.mkdir()
        args = [BPB, "generate", "--out", str(scratch / "ds"), "--per-horizon", "30",
                "--workers", "2", "--no-images"]  # fmt: skip
        code, stderr = ctrl_c_at_worker_start(args, 2, scratch)
        partial = scratch / ".ds.partial"
        assert (code, stderr.strip()) == (130, f"aborted; {left_in(partial)}")
        assert not (scratch / "ds").exists()


def left_in(partial: Path) -> str:
    return (
        f"the unfinished dataset is left in {partial} (delete it to free its space; running the "
        "command again starts it afresh)"
    )


@pytest.mark.skipif(not HAS_PROC, reason="lists children through /proc")
def test_ctrl_c_keeps_the_whole_scenes_made_and_leaves_the_dataset_it_was_to_overwrite(
    tmp_path: Path,
) -> None:
    """A terminal's Ctrl-C mid-run: exit 130 with a bare "aborted", saying nothing of the
    unfinished dataset it kept in a hidden folder. It now says where it is, as a write the
    system refused does; the scenes it lists there are whole, and --overwrite's dataset is
    untouched."""
    out, partial = tmp_path / "ds", tmp_path / ".ds.partial"
    args = [BPB, "generate", "--out", str(out), "--horizons", "1,2", "--no-images"]
    assert bpb(*args[1:], "--per-horizon", "2", "--workers", "1").returncode == 0
    before = tree(out)
    args += ["--per-horizon", "5000", "--workers", "2", "--overwrite"]  # about 20 s to finish
    process = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True, start_new_session=True,
                               preexec_fn=as_in_a_terminal)  # fmt: skip
    deadline = time.monotonic() + 120

    def scenes_on_disk() -> None:
        while len(list(partial.glob("h1/scene_*"))) < 50 and time.monotonic() < deadline:
            time.sleep(0.02)

    stderr = ctrl_c(process, 2, deadline, before=scenes_on_disk)
    assert process.returncode == 130, stderr  # 0: it finished before the Ctrl-C
    assert stderr.strip().splitlines() == [f"aborted; {out} is as it was, {left_in(partial)}"]
    assert tree(out) == before
    sums = [line.split("  ") for line in (partial / "checksums.sha256").read_text().splitlines()]
    for digest, rel in sums:
        assert hashlib.sha256((partial / rel).read_bytes()).hexdigest() == digest, rel
    listed = {rel for _, rel in sums}
    rows = (partial / "index.csv").read_text().splitlines()[1:]
    # some listed, not all 50 folders seen: a worker writes a scene before the parent lists it
    assert rows
    scene_files = {rel.rpartition("/")[2] for rel in before if rel.startswith("h1/scene_0000/")}
    assert scene_files
    for row in rows:  # each scene it lists holds what a finished dataset's scene holds
        label, index = row.split(",")[0].split("_")
        assert {f"{label}/scene_{index}/{name}" for name in scene_files} <= listed, row


@pytest.mark.skipif(not HAS_PROC, reason="reads signal dispositions through /proc")
def test_pool_workers_die_of_sigterm_whatever_handler_the_caller_set(tmp_path: Path) -> None:
    """Pool.terminate() stops the workers with SIGTERM. A Python handler of the caller's (a
    library caller's, bpb bench run's) was inherited by the workers, and one that took the
    signal just before blocking on the task queue never ran it: the generation hung at its end,
    1 in 5 paper-size datasets. Workers now have SIGTERM at its default."""
    import time

    script = (
        "import signal, sys\n"
        "from bpb_core.dataset import generate_dataset\n"
        "signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(143))\n"
        f"generate_dataset({str(tmp_path / 'ds')!r}, 100, [1, 2, 3, 4, 5], 0, workers=2)\n"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=as_in_a_terminal,  # SIGINT ignored marks a worker past its initializer
    )
    try:
        workers = settled_workers(process.pid, 2, time.monotonic() + 120)
        caught = [catches_sigterm(pid) for pid in workers]
        _, stderr = process.communicate(timeout=300)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 0, stderr
    assert len(workers) == 2 and caught == [False, False]


def test_calibrate_checks_the_image_margins_before_calibrating(tmp_path: Path) -> None:
    """--calibrate used to skip the margin check and make images with cut-off labels."""
    config = tmp_path / "narrow.json"
    config.write_text('{"image": {"margin_left": 40}, "calibration": {"samples": 20}}')
    # calibration refuses a horizon of 0.001 s: the margin error shows it never started
    done = bpb("generate", "--out", str(tmp_path / "ds"), "--per-horizon", "1", "--workers", "1",
               "--horizons", "0.001", "--calibrate", "--config", str(config))  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"error: {config}: image.margin_left: 40 px cuts off the image's labels or pockets at "
        "px_per_m 600 with pockets of radius 0.06 m (needs at least 116; leave it out for a "
        "margin that fits)"
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["narrow.json"]


def test_a_calibration_scene_the_simulator_cannot_finish_names_the_horizon_and_draw(
    tmp_path: Path,
) -> None:
    """A simulator's own refusal during --calibrate (pymunk's step too long for the fast cue
    of a short horizon) used to be "error: --dt: ..." with exit 3, as if bpb had a bug, naming
    neither the horizon nor the scene; generation says which scene it cannot finish. It then
    started "--calibrate: horizon ...", naming no file, where the same refusal of a dataset
    scene names the config file that sets the simulator; now it names it too."""
    config = tmp_path / "pymunk.json"
    config.write_text('{"simulator": "pymunk", "calibration": {"samples": 20, "iterations": 4}}')
    done = bpb("generate", "--out", str(tmp_path / "ds"), "--per-horizon", "1", "--workers", "2",
               "--horizons", "0.05", "--calibrate", "--config", str(config),
               "--no-images")  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"error: {config}: --calibrate: horizon 0.05 s: calibration draw 6 (cue at 15.5 m/s): "
        "dt: 0.001 s is above this scene's stability bound, 0.00092 s (half the ball radius, "
        "0.0142875 m, over the fastest possible speed, 15.52 m/s): a longer step can carry a "
        "ball through a cushion; the simulator cannot finish it: set dt in the config's "
        "simulator 'pymunk' (pymunk:dt=...)"
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pymunk.json"]


@pytest.mark.skipif(sys.platform == "win32", reason="runs bpb in a pseudo-terminal")
def test_the_progress_bar_shows_in_a_terminal_and_not_in_a_pipe(tmp_path: Path) -> None:
    """In a terminal the scenes' bar is drawn to the end; in a pipe or a log nothing is (and
    no bar is made at all: its cost showed in generation's CPU)."""
    import pty

    args = ["--per-horizon", "3", "--no-images", "--workers", "1"]
    leader, follower = pty.openpty()
    env = {**os.environ, "TERM": "xterm", "COLUMNS": "120"}
    command = [BPB, "generate", "--out", str(tmp_path / "tty"), *args]
    process = subprocess.Popen(command, stdin=follower, stdout=follower, stderr=follower, env=env)
    os.close(follower)
    shown = b""
    with contextlib.suppress(OSError):  # EIO once bpb has closed the terminal
        while chunk := os.read(leader, 65536):
            shown += chunk
    os.close(leader)
    assert process.wait(timeout=300) == 0, shown
    assert "15/15" in shown.decode(errors="replace")  # the bar, at its end
    piped = bpb("generate", "--out", str(tmp_path / "pipe"), *args)
    assert piped.returncode == 0 and piped.stderr == "", piped.stderr
