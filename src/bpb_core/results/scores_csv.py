"""``scores.csv``: the scored units of a run, written into its folder at the end of ``bpb run``."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from bpb_core.results.completeness import incomplete_lines
from bpb_core.results.frames import load_results
from bpb_core.results.tables import summary
from bpb_core.run_folder import write_bytes_atomic

if TYPE_CHECKING:
    import pandas as pd

    from bpb_core.dataset.reader import DataFolder
    from bpb_core.registry import Registry


def write_scores(
    run_dirs: Sequence[Path], registry: Registry | None = None, folders: Iterable[DataFolder] = ()
) -> pd.DataFrame | None:
    """Write ``scores.csv`` (scored units) into each run folder and return the summary table
    (``None`` when there is nothing to score); ``attrs["incomplete"]`` maps each run with
    unanswered calls to the line saying so. ``folders``: the runs' datasets, already read."""
    if not run_dirs:
        return None
    results = load_results(list(run_dirs), registry=registry, folders=folders)
    frame = results.units
    written = frame
    if (frame["epoch"] == 1).all():  # without --epochs the file keeps its columns
        written = frame.drop(columns="epoch")
    for run in results.runs:
        text = written[written["run"] == run.label].to_csv(index=False)
        write_bytes_atomic(run.path / "scores.csv", text.encode("utf-8"))
    table = summary(frame, results.suites)
    table.attrs["incomplete"] = incomplete_lines(results)  # what the summary must say
    return table
