"""Confusion tables of yes/no labels (Q1 over balls, Q2 per wall), shared by their diagnostics.

They look at *answered* units only: a unit the model did not label (missing answer, API or parse
error, duplicate or invalid label) says nothing about what it believes. Positive means ``T`` (a
contact happened).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pandas as pd

from bpb_core.results.tables import RUN_COLUMNS

if TYPE_CHECKING:
    from bpb_core.interfaces import ScoredResults

PERCENT = ("precision", "recall", "f1")


def labelled(units: pd.DataFrame, tasks: tuple[str, ...]) -> pd.DataFrame:
    """Units of ``tasks`` that carry a usable T/F label from an ok answer."""
    frame = units[units["task"].isin(tasks)]
    valid = (frame["status"] == "ok") & ~frame["duplicate"] & frame["pred"].isin(["T", "F"])
    return frame[valid]


def rates(counts: pd.DataFrame) -> pd.DataFrame:
    """Precision, recall and F1 from tp/fp/fn columns (NaN when undefined)."""
    tp, fp, fn = counts["tp"], counts["fp"], counts["fn"]
    precision = tp / (tp + fp).where(tp + fp > 0)
    recall = tp / (tp + fn).where(tp + fn > 0)
    f1 = 2 * precision * recall / (precision + recall).where(precision + recall > 0)
    return counts.assign(precision=precision, recall=recall, f1=f1)


def confusion(units: pd.DataFrame, task: str, *, per_unit: bool) -> pd.DataFrame:
    """Confusion counts with precision, recall and F1 for ``task``.

    Returns:
        Columns ``run, adapter, model, baseline, task, unit, tp, fp, fn, tn, precision, recall,
        f1``: one ``unit == "all"`` row per run pooling every unit, and with ``per_unit`` one
        row per unit (wall) too.
    """
    frame = labelled(units, (task,))
    truth = frame["truth"] == "T"
    pred = frame["pred"] == "T"
    flags = pd.DataFrame(
        {"tp": truth & pred, "fp": ~truth & pred, "fn": truth & ~pred, "tn": ~truth & ~pred}
    ).astype("int64")
    keyed = pd.concat([frame[[*RUN_COLUMNS, "task", "unit"]], flags], axis=1)
    parts = [keyed.assign(unit="all"), keyed] if per_unit else [keyed.assign(unit="all")]
    both = pd.concat(parts, ignore_index=True)
    counts = both.groupby([*RUN_COLUMNS, "task", "unit"], observed=True).sum().reset_index()
    return rates(counts)


class ConfusionDiagnostic:
    """Base of the Q1 and Q2 confusion diagnostics."""

    name = ""
    title = ""
    task = ""
    per_unit = False
    percent: tuple[str, ...] = PERCENT
    terminal: tuple[str, ...] = ()

    def table(self, results: ScoredResults) -> pd.DataFrame:
        """The confusion table of :attr:`task` (see :func:`confusion`)."""
        return confusion(results.units, self.task, per_unit=self.per_unit)

    def chart(self, table: pd.DataFrame) -> bytes | None:
        """No chart: the table says it."""
        return None
