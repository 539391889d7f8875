"""Benchmarks behind ``bpb bench ...``, one module each (``generate``, ``run``, ``score``,
``sim``, ``startup``), and the machine record every figure carries.

They reach scene families, simulators, tasks and scorers through the registry only, so a
benchmark measures whatever plugins are installed. Nothing here prints; the CLI shows results.
"""

from __future__ import annotations

import os
import platform
from datetime import date
from pathlib import Path

MAX_REPEATS = 100  # timed repeats of a benchmark: more take minutes for no better best time


def machine_description() -> str:
    """``2 cores, <CPU model>, CPython 3.11.7``: the machine a figure was measured on."""
    model = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    python = f"{platform.python_implementation()} {platform.python_version()}"
    return f"{os.cpu_count()} cores, {model}, {python}"


def today() -> str:
    """Today's date in ISO form (``2026-11-21``), the date a figure was measured."""
    return date.today().isoformat()
