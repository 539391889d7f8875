"""Results split by the dataset their runs answered: runs on different datasets answered
different questions, so no table ranks them together."""

from __future__ import annotations

from typing import TYPE_CHECKING

from bpb_core.results.frames import Results

if TYPE_CHECKING:
    import pandas as pd


def by_dataset(results: Results) -> list[Results]:
    """``results`` split by dataset (the hash each run records): runs on different datasets
    answered different questions, so they are never ranked together. Datasets in the order
    their first run was read."""
    datasets = list(dict.fromkeys(run.dataset_id for run in results.runs))
    if len(datasets) <= 1:
        return [results]
    parts = []
    for dataset in datasets:
        runs = tuple(run for run in results.runs if run.dataset_id == dataset)
        units = _only(results.units, dataset)
        calls = _only(results.calls, dataset)
        tasks = {str(t) for t in units["task"].unique()}
        suites = tuple(s for s in results.suites if set(s.weights) <= tasks)
        parts.append(Results(units, calls, runs, suites))
    return parts


def _only(frame: pd.DataFrame, dataset: str) -> pd.DataFrame:
    import pandas as pd

    part = frame[frame["dataset"] == dataset].reset_index(drop=True)
    for name in part.columns:
        if isinstance(part[name].dtype, pd.CategoricalDtype):
            part[name] = part[name].cat.remove_unused_categories()
    return part
