"""Evaluation runs: ask model adapters a dataset's tasks, resumably (:func:`run_eval`)."""

from bpb_core.runner.options import (
    NoProgress,
    Progress,
    ProgressEvent,
    RetryPolicy,
    RunOptions,
    RunResult,
)
from bpb_core.runner.run import evaluate, run_eval, run_eval_async, slug

__all__ = [
    "NoProgress",
    "Progress",
    "ProgressEvent",
    "RetryPolicy",
    "RunOptions",
    "RunResult",
    "evaluate",
    "run_eval",
    "run_eval_async",
    "slug",
]
