"""The library face: what other programs call to generate, simulate, run and report.

Everything here is re-exported by :mod:`bpb_core` (lazily, so ``import bpb_core`` stays cheap);
the CLI is a thin wrapper over the same functions. Each one reaches scene families, tasks,
simulators, adapters, scorers, suites and diagnostics through a registry (``registry=``; default:
every installed plugin).
"""

from __future__ import annotations

from bpb_core.dataset.generate import generate_dataset
from bpb_core.dataset.reader import Dataset, load_dataset
from bpb_core.dataset.scene_entry import DatasetScene
from bpb_core.library.answers import (
    AnswerScore,
    UnitScore,
    answer_schema,
    build_messages,
    score_answer,
)
from bpb_core.library.evaluation import (
    EvalResult,
    evaluate,
    evaluate_async,
    leaderboard,
    run_eval,
    run_eval_async,
)
from bpb_core.library.hf_export import HfExport, export_hf
from bpb_core.report.build import Report, build_report
from bpb_core.results.frames import Results, load_frame, load_results
from bpb_core.results.tables import summary
from bpb_core.simulate import simulate_lines, simulate_paths

__all__ = [
    "AnswerScore",
    "Dataset",
    "DatasetScene",
    "EvalResult",
    "HfExport",
    "Report",
    "Results",
    "UnitScore",
    "answer_schema",
    "build_messages",
    "build_report",
    "evaluate",
    "evaluate_async",
    "export_hf",
    "generate_dataset",
    "leaderboard",
    "load_dataset",
    "load_frame",
    "load_results",
    "run_eval",
    "run_eval_async",
    "score_answer",
    "simulate_lines",
    "simulate_paths",
    "summary",
]
