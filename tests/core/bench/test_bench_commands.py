"""``bpb bench``, ``bench startup``, ``bench generate`` and ``bench run`` through the real CLI,
at tiny sizes."""

from __future__ import annotations

import contextlib
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bpb_core.registry import Registry
from support.processes import HAS_PROC, as_in_a_terminal, children, ctrl_c, group_members

BENCHMARKS = ("extract", "generate", "run", "score", "sim", "startup")


def test_bench_help_lists_every_benchmark_without_importing_one() -> None:
    probe = (
        "import sys\nfrom bpb_core.cli.main import cli\n"
        "try:\n    cli.main(['bench', '--help'], standalone_mode=False)\n"
        "except SystemExit:\n    pass\n"
        "print(' '.join(m for m in sys.modules if m.startswith(('bpb_core.bench', "
        "'bpb_core.cli.bench.'))))"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    *help_text, imported = done.stdout.splitlines()
    listed = [line.split()[0] for line in help_text if line.startswith("  ") and line.split()]
    assert [name for name in listed if name in BENCHMARKS] == list(BENCHMARKS)
    assert imported == ""


def test_unknown_benchmark_is_a_usage_error(bench: Callable[..., Any]) -> None:
    done = bench("nosuch")
    assert done.returncode == 2 and "nosuch" in done.stderr


def test_bench_extract_times_every_adversarial_family(bench: Callable[..., Any]) -> None:
    from bpb_core.bench.extract import FAMILIES

    done = bench("extract", "--repeats", "1")
    assert done.returncode in (0, 1), done.stderr  # 1: slower than the target on a busy machine
    for family in FAMILIES:
        assert len(done.row(family)) == 4, family


def test_bench_startup_reports_medians_and_their_difference(bench: Callable[..., Any]) -> None:
    done = bench("startup", "--runs", "2")
    assert done.returncode == 0, done.stderr
    assert "2 interleaved runs" in done.stdout
    bare, help_ms, version = (
        float(done.row(c)[0]) for c in ("python -c pass", "bpb --help", "bpb --version")
    )
    assert 0 < bare < 5000 and 0 < help_ms < 5000 and 0 < version < 5000
    overhead = float(done.row("overhead of bpb --help")[0])
    assert abs(overhead - (help_ms - bare)) <= 0.11  # each figure is rounded to 0.1 ms


def test_bench_generate_times_each_variant(bench: Callable[..., Any], registry: Registry) -> None:
    done = bench("generate", "--per-horizon", "2", "--workers", "1")
    assert done.returncode == 0, done.stderr
    images = len(registry.scene_family(registry.default_family()).image_names) * 10
    assert f"10 scenes, {images} images of " in done.stdout and "1 worker" in done.stdout
    assert len(done.rows) == 4
    for name, seconds, per_scene in done.rows:
        assert float(seconds) > 0, name
        # ms per scene of 10 scenes; seconds are rounded to 0.01
        assert abs(float(per_scene) - 100 * float(seconds)) <= 0.51, name
    with_images = done.rows[0][1]
    assert float(with_images) > float(done.row("bpb generate --no-images")[0])


def test_bench_generate_memory_states_no_worker_peak_without_workers(
    bench: Callable[..., Any],
) -> None:
    done = bench("generate", "--per-horizon", "1", "--workers", "1", "--memory", "1")
    assert done.returncode == 0, done.stderr
    seconds, parent, worker = done.row("5")
    assert float(seconds) > 0 and float(parent) > 10
    assert worker == "–"  # one worker makes the scenes in the parent: no worker to measure


def test_bench_generate_rejects_bad_sizes(bench: Callable[..., Any]) -> None:
    done = bench("generate", "--per-horizon", "0")
    assert done.returncode == 2 and "--per-horizon" in done.stderr


def test_bench_run_counts_every_request_of_both_clients(
    tmp_path: Path, bench: Callable[..., Any], registry: Registry
) -> None:
    args = ["--concurrency", "4", "--latency", "0.05", "--throughput-scenes", "1"]
    args += ["--memory-scenes", "1", "--rounds", "1", "--work", str(tmp_path)]
    done = bench("run", *args)
    assert done.returncode == 0, done.stderr + done.stdout
    assert re.search(r"generating 5 scenes with images in .*bench-run-data-1", done.stderr)
    calls = len(registry.tasks_for(registry.default_family(), default_only=True)) * 5
    assert float(done.row("ideal")[2]) == 80.0  # 4 in flight / 0.05 s
    for client in ("bare litellm loop", "bpb run", "bpb run (memory)"):
        requests, seconds, rate, *_, rss, code = done.row(client)
        assert (int(requests), code) == (calls, "0"), client
        assert float(rate) > 0 and float(seconds) > 0 and float(rss) > 10, client
    for client in ("bare litellm loop", "bpb run"):  # the memory run has no latency to wait
        assert float(done.row(client)[2]) <= 80.0, client  # the server's delay bounds the rate
    assert (tmp_path / "bench-run-data-1" / "dataset.json").is_file()  # kept for reuse


def test_bench_run_shows_no_figures_for_a_client_that_failed(
    tmp_path: Path, bench: Callable[..., Any]
) -> None:
    from bpb_core.dataset import generate_dataset

    data = generate_dataset(tmp_path / "bench-run-data-1", 1, [1, 2, 3, 4, 5], seed=0)
    (data / "h2" / "scene_0000" / "init.png").write_bytes(b"not a png")  # bpb run stops here
    args = ["--concurrency", "4", "--latency", "0.01", "--throughput-scenes", "1"]
    done = bench("run", *args, "--memory-scenes", "0", "--rounds", "1", "--work", tmp_path)
    assert done.returncode == 1, done.stderr + done.stdout
    requests, *figures, code = done.row("bpb run")
    assert int(requests) >= 0 and code == "2"
    assert figures == ["–"] * 5  # no seconds, rate, shares or memory of a failed run
    assert float(done.row("bare litellm loop")[2]) > 0  # the bare loop reads one scene only
    said = " ".join(done.stderr.split())  # rich wraps long lines
    assert re.search(r"bpb run failed \(exit 2\): error: .*init\.png", said)


def test_bench_run_refuses_a_latency_no_call_outlives_and_a_work_path_under_a_file(
    tmp_path: Path, bench: Callable[..., Any]
) -> None:
    in_the_way = tmp_path / "notes.txt"
    in_the_way.write_text("a file")
    cases = [
        (("--latency", "inf"), "error: --latency: must be at least 0 and below the clients' 60"),
        (("--latency", "60"), "error: --latency: must be at least 0 and below"),
        (("--work", in_the_way / "w"), f"error: {in_the_way}: --work: not a folder"),
    ]
    for option, message in cases:  # refused at once: inf used to wait for ever
        done = bench("run", "--memory-scenes", "0", "--work", tmp_path / "w", *option, timeout=60)
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1, done.stderr
        assert lines[0].startswith(message), lines
    assert [p.name for p in tmp_path.iterdir()] == ["notes.txt"]  # nothing generated


@pytest.mark.skipif(not HAS_PROC, reason="lists children through /proc")
def test_a_terminated_bench_run_stops_its_fake_server_and_client(tmp_path: Path) -> None:
    import os
    import signal
    import time

    from bpb_core.dataset import generate_dataset

    generate_dataset(tmp_path / "bench-run-data-1", 1, [1, 2, 3, 4, 5], seed=0)
    bpb = str(Path(sys.executable).with_name("bpb"))
    args = [bpb, "bench", "run", "--latency", "5", "--throughput-scenes", "1"]
    args += ["--memory-scenes", "0", "--rounds", "1", "--work", str(tmp_path)]
    process = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               start_new_session=True)  # fmt: skip
    try:
        deadline = time.monotonic() + 120  # a condition, not a delay: generous for a busy CI
        while time.monotonic() < deadline and len(children(process.pid)) < 2:
            time.sleep(0.05)
        # the server and the bare loop, which may be between its fork and its exec: a SIGTERM
        # then left it running for ever
        assert len(children(process.pid)) == 2
        process.send_signal(signal.SIGTERM)  # a kill or a cancelled CI job, not a Ctrl-C
        assert process.wait(timeout=60) == 128 + signal.SIGTERM
        # the bench waits for the children it stops: none may be left once it has ended
        assert group_members(process.pid) == [], "left running after the bench ended"
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)


@pytest.mark.skipif(not HAS_PROC, reason="lists children through /proc")
def test_ctrl_c_during_the_pillow_timing_is_left_to_the_parent(tmp_path: Path) -> None:
    """The Pillow pool's workers printed a traceback each when Ctrl-C reached them."""
    import os
    import time

    bpb = str(Path(sys.executable).with_name("bpb"))
    args = [bpb, "bench", "generate", "--per-horizon", "20", "--workers", "2"]
    env = {**os.environ, "TMPDIR": str(tmp_path)}  # the datasets' folder goes before Pillow's
    process = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True, env=env, start_new_session=True,
                               preexec_fn=as_in_a_terminal)  # fmt: skip
    deadline = time.monotonic() + 120

    def made_and_gone() -> None:  # the datasets' folder is made, then removed before timing
        made = False
        while time.monotonic() < deadline and not (made and not any(tmp_path.iterdir())):
            made = made or any(tmp_path.iterdir())
            time.sleep(0.02)

    stderr = ctrl_c(process, 2, deadline, before=made_and_gone)
    assert process.returncode == 130, stderr
    assert stderr.strip() == "aborted"
