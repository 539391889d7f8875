"""Start-up time of the ``bpb`` command beside a bare interpreter.

Usage: ``python benchmarks/startup.py [--runs N]`` (default 20), with the interpreter whose
``bpb`` script is measured (the one next to ``sys.executable``). ``python -c pass``, ``bpb
--help`` and ``bpb --version`` run in turn, interleaved so that machine noise hits all three
alike; the medians in milliseconds are printed, and the overhead of ``bpb --help`` (target: at
most 300 ms).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path


def wall_ms(argv: list[str]) -> float:
    """Milliseconds of one run of ``argv`` to its exit (output thrown away)."""
    started = time.perf_counter()
    subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return (time.perf_counter() - started) * 1000.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20, help="interleaved runs")
    runs = max(1, parser.parse_args().runs)
    bpb = str(Path(sys.executable).with_name("bpb"))
    commands = {
        "python -c pass": [sys.executable, "-c", "pass"],
        "bpb --help": [bpb, "--help"],
        "bpb --version": [bpb, "--version"],
    }
    samples: dict[str, list[float]] = {name: [] for name in commands}
    for _ in range(runs):
        for name, argv in commands.items():
            samples[name].append(wall_ms(argv))
    median = {name: statistics.median(values) for name, values in samples.items()}
    print(f"bpb start-up, medians of {runs} interleaved runs")
    for name, ms in median.items():
        print(f"{name:24}{ms:10.1f} ms")
    overhead = median["bpb --help"] - median["python -c pass"]
    print(f"{'overhead of bpb --help':24}{overhead:10.1f} ms")


if __name__ == "__main__":
    main()
