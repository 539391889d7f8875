"""``bpb run`` through the real entry point: resume after kill -9, exit codes, dry run.

The commands run in this process (:mod:`support.inprocess`), but for the runs stopped by a
signal, which are processes of their own."""

from __future__ import annotations

import functools
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from bpb_core.errors import BadInput
from bpb_core.registry import Registry
from bpb_core.run_folder import iter_answers
from bpb_core.runner import run_eval
from support.fake_openai import fake_server
from support.inprocess import Done, bpb

BPB = str(Path(sys.executable).parent / "bpb")
KEY = "sk-bpbtest-0123456789abcdefSECRET"


def _env() -> dict[str, str]:
    return {**os.environ, "OPENAI_API_KEY": KEY, "COLUMNS": "200"}


@pytest.fixture
def cli(capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> Callable[..., Done]:
    """``bpb ARGS`` in this process, with the environment of :func:`_env`."""
    monkeypatch.setenv("OPENAI_API_KEY", KEY)
    monkeypatch.setenv("COLUMNS", "200")
    return functools.partial(bpb, capfd)


def _complete(run_dir: Path) -> set[str]:
    return {f"{r.scene_id}/{r.task}" for _, r in iter_answers(run_dir) if r.status == "ok"}


@pytest.mark.slow
def test_kill_9_then_same_command_never_resends_completed(
    cli: Callable[..., Done], dataset: Path, tmp_path: Path
) -> None:
    with fake_server(dataset, {"latency": 0.3}, tmp_path) as server:
        args = [
            "run",
            "--data",
            str(dataset),
            "--adapter",
            "litellm:openai/fake-model",
            "--api-base",
            server.api_base,
            "--out",
            str(tmp_path / "out"),
            "--concurrency",
            "2",
            "--timeout",
            "10",
        ]
        run_dir = tmp_path / "out" / "litellm_openai_fake-model"
        process = subprocess.Popen(
            [BPB, *args], env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        deadline = time.time() + 60
        while len(_complete(run_dir)) < 5 and time.time() < deadline:
            time.sleep(0.05)
        process.send_signal(signal.SIGKILL)
        process.wait()
        done_at_kill = _complete(run_dir)
        counts_at_kill = server.counts()
        assert 5 <= len(done_at_kill) < 18
        finished = cli(*args)
        assert finished.returncode == 0, finished.stderr
        counts = server.counts()
        assert len(_complete(run_dir)) == 18
        for key in done_at_kill:
            assert counts[key] == counts_at_kill[key] == 1, key
        assert len(counts) == 18  # every (scene, task) was asked
        # only calls in flight at the kill (at most --concurrency 2) can have been paid twice
        assert sum(counts.values()) - 18 <= 2 and max(counts.values()) <= 2
        lines = (run_dir / "attempts.jsonl").read_text().splitlines()
        assert all(json.loads(line) for line in lines if line.strip())
        manifest = json.loads((run_dir / "run.json").read_text())
        assert len(manifest["sessions"]) == 2 and manifest["finished"]


@pytest.mark.slow
def test_sigterm_with_a_low_rpm_stops_once_the_calls_in_flight_finish(
    cli: Callable[..., Done], dataset: Path, tmp_path: Path
) -> None:
    # Calls queued for a rate-limit slot used to sleep until their slot before noticing the
    # stop: at --rpm 12 the 16 pairs left took 80 s to leave, at --rpm 6 the tester's ~160 s.
    with fake_server(dataset, {"latency": 1.0}, tmp_path) as server:
        args = ["run", "--data", str(dataset), "--adapter", "litellm:openai/fake-model",
                "--api-base", server.api_base, "--out", str(tmp_path / "out"),
                "--concurrency", "4"]  # fmt: skip
        run_dir = tmp_path / "out" / "litellm_openai_fake-model"
        process = subprocess.Popen(
            [BPB, *args, "--rpm", "12"],  # one call starts every 5 s
            env=_env(),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        deadline = time.time() + 60
        while server.stats()["total"] < 2 and time.time() < deadline:
            time.sleep(0.05)
        process.send_signal(signal.SIGTERM)  # the second call is in flight (1 s latency)
        try:
            _, stderr = process.communicate(timeout=40)  # the bug took 80 s; a busy CI, ~5
        except subprocess.TimeoutExpired:
            process.kill()
            process.communicate()
            pytest.fail("bpb run was still running 40 s after SIGTERM")
        assert process.returncode == 1, stderr
        asked = server.counts()
        assert len(asked) == 2 and set(asked) == _complete(run_dir)  # the one in flight is kept
        assert json.loads((run_dir / "run.json").read_text())["stopped"] == "interrupted"
        resumed = cli(*args)  # the same command (no --rpm, to be quick) sends the rest once
        assert resumed.returncode == 0, resumed.stderr
        counts = server.counts()
        assert len(counts) == 18 and set(counts.values()) == {1}
        assert len(_complete(run_dir)) == 18


def test_unknown_adapter_or_task_is_one_line_exit_2(
    cli: Callable[..., Done], dataset: Path, tmp_path: Path
) -> None:
    bad = cli("run", "--data", str(dataset), "--adapter", "nope:x", "--out", str(tmp_path))
    assert bad.returncode == 2
    assert bad.stderr.strip().count("\n") == 0 and "baseline" in bad.stderr
    assert "litellm" in bad.stderr
    bad = cli("run", "--data", str(dataset), "--tasks", "q1,q9", "--out", str(tmp_path))
    assert bad.returncode == 2 and "q9" in bad.stderr and "q3" in bad.stderr
    bad = cli(
        "run", "--data", str(dataset), "--adapter", "baseline:psychic", "--out", str(tmp_path)
    )
    assert bad.returncode == 2 and "baseline:oracle" in bad.stderr


def test_auth_error_exits_2_with_a_clear_message(
    cli: Callable[..., Done], dataset: Path, tmp_path: Path
) -> None:
    with fake_server(dataset, {"faults": {"*/q1": ["401"] * 20}}, tmp_path) as server:
        done = cli(
            "run",
            "--data",
            str(dataset),
            "--adapter",
            "litellm:openai/fake-model",
            "--api-base",
            server.api_base,
            "--out",
            str(tmp_path / "o"),
            "--tasks",
            "q1",
        )
    assert done.returncode == 2
    assert "authentication failed" in done.stderr and KEY not in done.stderr + done.stdout


def test_dry_run_sends_nothing(cli: Callable[..., Done], dataset: Path, tmp_path: Path) -> None:
    with fake_server(dataset) as server:
        done = cli(
            "run",
            "--data",
            str(dataset),
            "--adapter",
            "litellm:openai/fake-model",
            "--api-base",
            server.api_base,
            "--out",
            str(tmp_path),
            "--dry-run",
        )
        assert done.returncode == 0, done.stderr
        assert server.stats()["total"] == 0
    lines = done.stdout.splitlines()
    rows = [line.split("│") for line in lines if "fake-model│" in line.replace(" ", "")]
    table = {cells[2].strip(): [c.strip() for c in cells[3:6]] for cells in rows}
    assert sorted(table) == ["q1", "q2", "q3"]
    for task, (calls, before, tokens) in table.items():
        assert (calls, before) == ("6", "0"), task  # 6 scenes, none done before
        assert int(tokens.replace(",", "")) > 6 * 300, task  # prompt text plus an image each
    assert not (tmp_path / "litellm_openai_fake-model" / "attempts.jsonl").exists()


def test_default_run_is_the_baseline_leaderboard(
    cli: Callable[..., Done], dataset: Path, tmp_path: Path
) -> None:
    done = cli("run", "--data", str(dataset), "--out", str(tmp_path), "--cot", "q1")
    assert done.returncode == 0, done.stderr
    for name in ("stasis", "straight", "random", "oracle"):
        assert f"baseline:{name}" in done.stdout
        assert (tmp_path / f"baseline_{name}" / "scores.csv").exists()
    manifest = json.loads((tmp_path / "baseline_oracle" / "run.json").read_text())
    assert manifest["options"]["cot"] == {"q1": True, "q2": False, "q3": False}
    changed = cli("run", "--data", str(dataset), "--out", str(tmp_path), "--input-mode", "state")
    assert changed.returncode == 2 and "input_mode" in changed.stderr


def _gone_simulator(dataset: Path, tmp_path: Path) -> Path:
    """A copy of ``dataset`` whose dataset.json names a simulator that is not installed."""
    data = Path(shutil.copytree(dataset, tmp_path / "data"))
    manifest = json.loads((data / "dataset.json").read_text())
    manifest["config"] = {"simulator": "uninstalled-sim"}
    (data / "dataset.json").write_text(json.dumps(manifest))
    return data


def test_a_dataset_naming_an_uninstalled_simulator_refuses_the_oracle_only(
    cli: Callable[..., Done], dataset: Path, tmp_path: Path
) -> None:
    # The oracle run started anyway (its folder made, the stasis run before it done) and failed
    # at its first call, on the missing simulator.
    data, out = _gone_simulator(dataset, tmp_path), tmp_path / "out"
    refused = cli("run", "--data", str(data), "--adapter", "baseline:stasis",
                   "--adapter", "baseline:oracle", "--out", str(out))  # fmt: skip
    assert refused.returncode == 2, refused.stderr
    assert refused.stderr.strip().splitlines() == [
        f"error: {data}/dataset.json: config: names simulator 'uninstalled-sim', which is not "
        "installed (installed: analytic, pymunk); baseline:oracle runs it"
    ]
    assert not out.exists()  # before any adapter's first call
    stasis = cli("run", "--data", str(data), "--adapter", "baseline:stasis", "--out", str(out))
    assert stasis.returncode == 0, stasis.stderr  # it needs no simulator
    default = cli("run", "--data", str(data), "--out", str(tmp_path / "default"))
    assert default.returncode == 0, default.stderr
    assert "note: left out: " in default.stderr and "baseline:oracle runs it" in default.stderr
    assert (tmp_path / "default" / "baseline_stasis" / "scores.csv").exists()
    assert not (tmp_path / "default" / "baseline_oracle").exists()


def test_image_input_on_a_dataset_generated_without_images_is_refused_before_the_run_folder(
    cli: Callable[..., Done], tmp_path: Path, registry: Registry
) -> None:
    # bpb run made the run folder (run.json, attempts.jsonl, run.lock), then failed on the
    # first scene's "init.png: missing".
    data, out = tmp_path / "bare", tmp_path / "out"
    made = cli("generate", "--out", str(data), "--per-horizon", "2", "--horizons", "1",
                "--no-images", "--workers", "1")  # fmt: skip
    assert made.returncode == 0, made.stderr
    line = (
        f"{data}: generated with --no-images (dataset.json: images: false), so it has no "
        "images to show; use input mode 'state' (--input-mode state)"
    )
    for extra in ([], ["--dry-run"], ["--input-mode", "image+state"]):
        refused = cli("run", "--data", str(data), "--adapter", "baseline:stasis",
                       "--out", str(out), *extra)  # fmt: skip
        assert refused.returncode == 2, refused.stderr
        assert refused.stderr.strip().splitlines() == [f"error: {line}"]
        assert not out.exists()
    with pytest.raises(BadInput) as refusal:
        run_eval(data, "baseline:stasis", out, registry=registry)
    assert str(refusal.value) == line
    assert not out.exists()
    state = cli("run", "--data", str(data), "--adapter", "baseline:stasis", "--out", str(out),
                 "--input-mode", "state")  # fmt: skip
    assert state.returncode == 0, state.stderr


READS: list[list[str]] = []  # the reads of dataset.json seen while a list is pushed here


def _reads_of_manifest(event: str, args: tuple[object, ...]) -> None:
    if event != "open" or not READS or not str(args[0]).endswith("dataset.json"):
        return
    mode, flags = args[1], args[2]
    reading = "r" in mode and "+" not in mode if isinstance(mode, str) else None
    if reading is None and isinstance(flags, int):  # os.open
        reading = flags & os.O_ACCMODE == os.O_RDONLY
    if reading:
        READS[-1].append(str(args[0]))


sys.addaudithook(_reads_of_manifest)  # hooks stay for the process; it counts only when asked


def _manifest_reads(argv: list[str]) -> int:
    from bpb_core.cli.main import main

    READS.append([])
    try:
        with pytest.raises(SystemExit) as done:
            main(argv)
    finally:
        seen = READS.pop()
    assert done.value.code == 0
    return len(seen)


def test_each_command_reads_dataset_json_once(tmp_path: Path) -> None:
    """The dataset is read once into one value that every check of the command is given (a
    2-scene bpb run read it 6 times, a report once per run and again for its family)."""
    data, runs = str(tmp_path / "data"), str(tmp_path / "runs")
    generate = ["generate", "--out", data, "--per-horizon", "2", "--horizons", "1",
                "--no-images", "--workers", "1"]  # fmt: skip
    assert _manifest_reads(generate) == 1  # the summary it prints
    run = ["run", "--data", data, "--out", runs, "--input-mode", "state"]  # every offline adapter
    assert _manifest_reads(run) == 1  # the checks, run.json's hash, the scores it prints
    assert len(list(Path(runs).iterdir())) >= 2
    assert _manifest_reads(["report", runs, "--out", str(tmp_path / "report")]) == 1
