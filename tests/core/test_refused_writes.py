"""A disk that fills up (here: a file size limit) part-way through a command that writes
results: one line naming the file and what is kept where, exit 2, nothing already done lost."""

from __future__ import annotations

import resource
import signal
import subprocess
import sys
from pathlib import Path
from typing import IO

import pytest

from bpb_core.run_folder import read_attempts
from support.fake_openai import fake_server
from support.paths import tree

BPB = str(Path(sys.executable).with_name("bpb"))
pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="rlimits are POSIX")


def bpb(
    *args: str, limit: int | None = None, stdout: IO[bytes] | None = None
) -> subprocess.CompletedProcess[str]:
    """``bpb ARGS``; with ``limit``, no file it writes may grow past ``limit`` bytes (a write
    past it fails with EFBIG, as one on a full disk fails with ENOSPC); its output goes to
    ``stdout`` when given (as with ``> file``), else is captured."""

    def limited() -> None:
        if limit is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return subprocess.run(
        [BPB, *args],
        stdout=subprocess.PIPE if stdout is None else stdout,
        stderr=subprocess.PIPE,
        text=True,
        timeout=300,
        preexec_fn=limited,
    )


def answers(run_dir: Path) -> dict[str, bytes]:
    return {p.relative_to(run_dir).as_posix(): p.read_bytes() for p in run_dir.glob("h*/*/*.json")}


def test_a_run_the_disk_cuts_short_keeps_its_answers_and_says_how_to_resume(
    dataset: Path, tmp_path: Path
) -> None:
    """It was "internal error: OSError: [Errno 27] File too large" (exit 3), naming no file."""
    run = ["run", "--data", str(dataset), "--adapter", "baseline:stasis", "--out", str(tmp_path)]
    run_dir = tmp_path / "baseline_stasis"
    first = bpb(*run, "--limit", "1")  # 6 of 18 pairs; its attempts log: about 6 kB
    assert first.returncode == 0, first.stderr
    before = answers(run_dir)
    done = bpb(*run, limit=12_000)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines()[-1] == (
        f"error: {run_dir / 'attempts.jsonl'}: cannot write: [Errno 27] File too large; the run "
        f"stopped, and {run_dir} keeps every answer written so far: make room, then re-run the "
        "same command to resume"
    )
    kept = answers(run_dir)
    assert len(before) == 6 and len(before) < len(kept) < 18
    assert {name: kept[name] for name in before} == before
    resumed = bpb(*run)
    assert resumed.returncode == 0, resumed.stderr
    assert answers(run_dir).items() >= kept.items() and len(answers(run_dir)) == 18


def test_a_disk_full_before_the_run_starts_is_one_line_naming_the_lock(
    dataset: Path, tmp_path: Path
) -> None:
    """It was "internal error: OSError: [Errno 27] File too large" (exit 3): the pid written
    into ``run.lock`` was the first write, and nothing guarded it."""
    out = tmp_path / "out"
    done = bpb("run", "--data", str(dataset), "--adapter", "baseline:stasis", "--out", str(out),
               limit=0)  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"error: {out / 'baseline_stasis' / 'run.lock'}: cannot write: [Errno 27] File too "
        "large; nothing was sent: make room, then run again"
    ]


def test_no_call_is_sent_after_the_disk_refuses_a_write(
    dataset: Path, tmp_path: Path, secret_key: str
) -> None:
    """The calls queued for a slot went out after the first refused write, each paid for and
    none kept (25 sent, 9 kept). One call at a time, the call whose reply could not be logged
    is the last one the server sees."""
    out = tmp_path / "out"
    with fake_server(dataset, {"latency": 0.05}, tmp_path) as server:
        done = bpb(
            "run", "--data", str(dataset), "--adapter", "litellm:openai/fake-model",
            "--api-base", server.api_base, "--concurrency", "1", "--out", str(out),
            limit=5_000,  # run.json (under 4 kB) fits; the attempts log: about 4 lines of 18
        )  # fmt: skip
        sent = server.stats()["total"]
    run_dir = out / "litellm_openai_fake-model"
    assert done.returncode == 2, done.stderr
    refused = f"error: {run_dir / 'attempts.jsonl'}: cannot write: [Errno 27] File too large"
    assert done.stderr.strip().splitlines()[-1].startswith(f"{refused}; the run stopped")
    kept = len(list(read_attempts(run_dir)))
    assert 1 <= kept < 18
    assert sent == kept + 1


def test_a_report_the_disk_cuts_short_names_the_file_and_leaves_the_runs_alone(
    runs: Path, tmp_path: Path
) -> None:
    """report.html (about 550 kB) over a 200,000-byte limit, after the charts (under 120 kB)."""
    before = tree(runs)
    out = tmp_path / "report"
    done = bpb("report", str(runs), "--out", str(out), limit=200_000)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines()[-1] == (
        f"error: {out / 'report.html'}: cannot write: [Errno 27] File too large; the report in "
        f"{out} is incomplete (the runs it reads are untouched): make room, then run it again"
    )
    assert (out / "charts" / "leaderboards.png").stat().st_size > 50_000
    assert tree(runs) == before


def test_an_export_the_disk_cuts_short_names_the_shard_and_keeps_the_earlier_export(
    small_dataset: Path, tmp_path: Path
) -> None:
    out = tmp_path / "export"
    first = bpb("export", str(small_dataset), "--out", str(out))
    assert first.returncode == 0, first.stderr
    before = tree(out)
    done = bpb("export", str(small_dataset), "--out", str(out), limit=50_000)  # shards: ~100 kB
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    partial = tmp_path / ".export.partial"
    [line] = done.stderr.strip().splitlines()
    assert line.startswith(
        f"error: {partial}/data/h1-00000-of-00001.parquet: cannot write: [Errno 27] "
    )  # then pyarrow's words, naming the error
    assert line.endswith(
        f"File too large; nothing was exported (the unfinished export in {partial} is "
        f"removed); {out} is as it was"
    )
    assert tree(out) == before and not partial.exists()


def test_simulate_output_the_disk_cuts_short_keeps_whole_lines_and_says_how_many(
    dataset: Path, tmp_path: Path
) -> None:
    """``bpb simulate ... > finals.jsonl`` was "internal error: OSError: [Errno 27] File too
    large" (exit 3), naming no file and not saying which scenes' lines were written."""
    scenes = sorted(str(p) for p in dataset.glob("h*/scene_*/init.json")) * 100  # 600 lines
    full = bpb("simulate", "--workers", "2", *scenes)
    assert full.returncode == 0, full.stderr
    lines = full.stdout.splitlines(keepends=True)
    assert len(lines) == 600
    limit = len("".join(lines[:515]).encode()) + 10  # in the second write (512 lines each)
    out = tmp_path / "finals.jsonl"
    with out.open("wb") as file:
        done = bpb("simulate", "--workers", "2", *scenes, limit=limit, stdout=file)
    assert done.returncode == 2, done.stderr
    [line] = done.stderr.strip().splitlines()
    assert line == (
        f"error: {out}: cannot write: [Errno 27] File too large; it holds the first 515 lines "
        "whole and the start of the next (one a scene, in input order): make room, then "
        "simulate the rest"
    )
    assert out.read_text() == "".join(lines[:515]) + lines[515][:10]
