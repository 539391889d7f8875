"""Start-up cost of the ``bpb`` command, measured beside a bare interpreter in one run."""

from __future__ import annotations

import statistics
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from bpb_core.bench.children import run_child


@dataclass(frozen=True)
class StartupResult:
    """Median wall times in milliseconds over ``runs`` interleaved runs."""

    runs: int
    bare_ms: float
    help_ms: float
    version_ms: float

    @property
    def overhead_ms(self) -> float:
        """``bpb --help`` minus ``python -c pass``."""
        return self.help_ms - self.bare_ms


def _time(argv: list[str]) -> float:
    started = time.perf_counter()
    run_child(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return (time.perf_counter() - started) * 1000.0


def measure_startup(runs: int = 20) -> StartupResult:
    """Time ``python -c pass``, ``bpb --help`` and ``bpb --version``, interleaved so that
    machine noise hits all three alike."""
    bpb = str(Path(sys.executable).with_name("bpb"))
    commands = {
        "bare": [sys.executable, "-c", "pass"],
        "help": [bpb, "--help"],
        "version": [bpb, "--version"],
    }
    samples: dict[str, list[float]] = {name: [] for name in commands}
    for _ in range(runs):
        for name, argv in commands.items():
            samples[name].append(_time(argv))
    med = {name: statistics.median(values) for name, values in samples.items()}
    return StartupResult(runs, med["bare"], med["help"], med["version"])
