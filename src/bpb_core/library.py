"""The library face: what other programs call to generate, simulate, run and report.

Everything here is re-exported by :mod:`bpb_core` (lazily, so ``import bpb_core`` stays cheap);
the CLI is a thin wrapper over the same functions. Each one reaches scene families, tasks,
simulators, adapters, scorers, suites and diagnostics through a registry (``registry=``; default:
every installed plugin).
"""

from __future__ import annotations

from bpb_core.dataset.generate import generate_dataset
from bpb_core.dataset.reader import Dataset, load_dataset
from bpb_core.report.build import Report, build_report
from bpb_core.results.frames import Results, load_frame, load_results
from bpb_core.results.tables import leaderboard, summary
from bpb_core.runner.run import evaluate, run_eval, run_eval_async
from bpb_core.simulate import simulate_lines, simulate_paths

__all__ = [
    "Dataset",
    "Report",
    "Results",
    "build_report",
    "evaluate",
    "generate_dataset",
    "leaderboard",
    "load_dataset",
    "load_frame",
    "load_results",
    "run_eval",
    "run_eval_async",
    "simulate_lines",
    "simulate_paths",
    "summary",
]
