"""The benchmark scripts at tiny sizes: each runs to the end and prints its figures.

Not part of the default test run (``testpaths`` is ``tests`` and ``plugins``); run them with
``pytest benchmarks/tests`` after ``pip install -e plugins/bpb-testing`` (``run.py`` starts the
fake server).
"""

from __future__ import annotations

import importlib.util
import random
import subprocess
import sys
from pathlib import Path
from types import ModuleType

HERE = Path(__file__).resolve().parents[1]


def script(name: str, *args: str | Path) -> subprocess.CompletedProcess[str]:
    argv = [sys.executable, str(HERE / f"{name}.py"), *map(str, args)]
    return subprocess.run(argv, capture_output=True, text=True, timeout=600)


def load(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, HERE / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_extract_times_every_adversarial_family_and_q1_reply() -> None:
    done = script("extract", "--repeats", "1")
    assert done.returncode in (0, 1), done.stderr  # 1: slower than the target on a busy machine
    module = load("extract")
    for family in [*module.FAMILIES, *module.Q1_REPLIES]:
        assert family in done.stdout, family


def test_startup_prints_the_overhead_of_bpb_help() -> None:
    done = script("startup", "--runs", "1")
    assert done.returncode == 0, done.stderr
    assert "overhead of bpb --help" in done.stdout


def test_generate_times_each_variant_and_the_memory() -> None:
    done = script("generate", "--per-horizon", "1", "--workers", "1", "--memory", "1")
    assert done.returncode == 0, done.stderr
    assert "5 scenes" in done.stdout and "Pillow alone" in done.stdout
    assert "memory, 5 scenes" in done.stdout and "largest worker - MiB" in done.stdout


def test_score_prints_two_rows_per_scored_task() -> None:
    done = script("score", "--rows", "1000", "--repeats", "1", "--per-horizon", "1")
    assert done.returncode == 0, done.stderr
    for task in ("q1", "q2", "q3"):
        rows = [line for line in done.stdout.splitlines() if line.startswith(f"{task} ")]
        assert len(rows) == 2, done.stdout


def test_score_corrupts_a_copy_by_one_entry() -> None:
    corrupt = load("score").corrupt
    answer = {"contacts": [1, 2, 3], "n": 4}
    changed = corrupt(answer, random.Random(0))
    assert answer == {"contacts": [1, 2, 3], "n": 4} and changed["n"] == 4
    assert abs(len(changed["contacts"]) - 3) == 1


def test_run_counts_every_request_of_both_clients(tmp_path: Path) -> None:
    args = ["--concurrency", "4", "--latency", "0.05", "--throughput-scenes", "1"]
    done = script("run", *args, "--memory-scenes", "1", "--rounds", "1", "--work", tmp_path)
    assert done.returncode == 0, done.stderr + done.stdout
    rows = {line[:20].strip(): line[20:].split() for line in done.stdout.splitlines()[2:]}
    for client in ("bare litellm loop", "bpb run", "bpb run (memory)"):
        assert rows[client][0] == rows["bpb run"][0] and int(rows[client][0]) > 0, client
        assert float(rows[client][-2]) > 10, client  # peak MiB of the client itself
