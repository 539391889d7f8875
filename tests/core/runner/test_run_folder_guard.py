"""Run folders that cannot be corrupted: a lock, two guards, recovery from the log, signals.

The run that is stopped, or that holds the folder, is a process of its own; the second run and
the resume run in this process (:mod:`support.inprocess`)."""

from __future__ import annotations

import functools
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from bpb_core.run_folder import iter_answers, read_attempts
from support.fake_openai import fake_server
from support.inprocess import Done, bpb

BPB = str(Path(sys.executable).parent / "bpb")
KEY = "sk-bpbtest-0123456789abcdefSECRET"
RUN = "litellm_openai_fake-model"


def _env() -> dict[str, str]:
    return {**os.environ, "OPENAI_API_KEY": KEY, "COLUMNS": "200"}


@pytest.fixture
def cli(capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> Callable[..., Done]:
    """``bpb ARGS`` in this process, with the environment of :func:`_env`."""
    monkeypatch.setenv("OPENAI_API_KEY", KEY)
    monkeypatch.setenv("COLUMNS", "200")
    return functools.partial(bpb, capfd)


def _args(dataset: Path, out: Path, api_base: str, *more: str) -> list[str]:
    return [BPB, "run", "--data", str(dataset), "--adapter", "litellm:openai/fake-model",
            "--api-base", api_base, "--out", str(out), "--timeout", "20", *more]  # fmt: skip


def _wait_for_attempts(run_dir: Path, count: int) -> None:
    deadline = time.time() + 60
    while sum(1 for _ in read_attempts(run_dir)) < count and time.time() < deadline:
        time.sleep(0.05)


@pytest.mark.slow
def test_a_second_run_on_the_folder_exits_2_and_no_call_is_paid_twice(
    cli: Callable[..., Done], dataset: Path, tmp_path: Path
) -> None:
    with fake_server(dataset, {"latency": 5}, tmp_path) as server:
        args = _args(dataset, tmp_path / "out", server.api_base, "--concurrency", "2")
        quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
        first = subprocess.Popen(args, env=_env(), **quiet)  # type: ignore[call-overload]
        try:
            deadline = time.monotonic() + 120  # a condition: a failed first run ends the wait
            while not (tmp_path / "out" / RUN / "run.json").exists() and first.poll() is None:
                assert time.monotonic() < deadline, "the first run made no run folder"
                time.sleep(0.05)
            second = cli(*args[1:])
            assert first.poll() is None  # the first run was still going (its calls are slow)
            server.configure({"faults": {}, "latency": 0})
            assert first.wait(timeout=120) == 0
        finally:
            first.kill()  # no-op when it ended; not left running when the test failed
            first.wait()
        counts = server.counts()
    assert second.returncode == 2
    line = second.stderr.strip()
    assert "\n" not in line and f"in use by another bpb run or bpb human (pid {first.pid})" in line
    assert len(counts) == 18 and set(counts.values()) == {1}  # zero calls paid twice
    assert not (tmp_path / "out" / RUN / "run.lock").read_text()  # released at the end


@pytest.mark.slow
def test_sigterm_stops_sending_records_stopped_and_the_resume_pays_nothing_twice(
    cli: Callable[..., Done], dataset: Path, tmp_path: Path
) -> None:
    with fake_server(dataset, {"latency": 0.5}, tmp_path) as server:
        args = _args(dataset, tmp_path / "out", server.api_base, "--concurrency", "2")
        run_dir = tmp_path / "out" / RUN
        pipes = {"stdout": subprocess.PIPE, "stderr": subprocess.PIPE, "text": True}
        process = subprocess.Popen(args, env=_env(), **pipes)  # type: ignore[call-overload]
        _wait_for_attempts(run_dir, 2)
        process.send_signal(signal.SIGTERM)
        _, err = process.communicate(timeout=120)
        assert process.returncode == 1, err
        assert "interrupted" in err and "re-run the same command to resume" in err
        manifest = json.loads((run_dir / "run.json").read_text())
        assert manifest["stopped"] == "interrupted" and manifest["finished"]
        logged = [f"{e['scene_id']}/{e['task']}" for e in read_attempts(run_dir)]
        written = {f"{r.scene_id}/{r.task}" for _, r in iter_answers(run_dir)}
        assert set(logged) == written and len(written) < 18  # every call paid for is written
        finished = cli(*args[1:])
        assert finished.returncode == 0, finished.stderr
        counts = server.counts()
    assert len(counts) == 18 and set(counts.values()) == {1}
    assert json.loads((run_dir / "run.json").read_text())["stopped"] is None
