"""Results: scored frames from run folders (:func:`load_results`) and the tables derived from
them."""

from bpb_core.results.frames import (
    CALL_DTYPES,
    META_DTYPES,
    Results,
    load_frame,
    load_results,
)
from bpb_core.results.reading import find_runs, read_run
from bpb_core.results.tables import leaderboard, summary

__all__ = [
    "CALL_DTYPES",
    "META_DTYPES",
    "Results",
    "find_runs",
    "leaderboard",
    "load_frame",
    "load_results",
    "read_run",
    "summary",
]
