"""The scorer of yes/no labels that Q1 (did the cue ball touch ball i?) and Q2 (did it touch
wall w?) share.

Rules, applied per unit (object ball or wall):

- A label is ``T`` or ``F``; case and surrounding spaces are ignored, ``TRUE``/``FALSE`` and JSON
  booleans are read as ``T``/``F``. Any other value is an invalid label and is wrong.
- A unit the answer does not mention is wrong; a unit mentioned twice or more is wrong, even when
  the copies agree (the answer is ambiguous).
- Entries for units the truth does not have (ball 0 or 7 in Q1, a ``MIDDLE`` wall) and extra keys
  inside an entry are ignored.
- Only answers with status ``ok`` can be right.

Q1 scores a scene by the share of its object balls that are right (per-ball accuracy); Q2 gives a
scene 1 only when all four walls are right (exact wall-set match). Keys are read with the one
rule of :mod:`bpb_tasks.questions.answers`.

The confusion tables of the labels (Q1 over balls, Q2 per wall) look at *answered* units only: a
unit the model did not label (missing answer, API or parse error, duplicate or invalid label)
says nothing about what it believes. Positive means ``T`` (a contact happened).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pandas as pd

from bpb_core.results.tables import RUN_COLUMNS
from bpb_core.scored_units import INVALID, UnitRow, entries
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.truth.final import FinalState

if TYPE_CHECKING:
    from bpb_core.interfaces import ScoredResults

_TRUE = {"T", "TRUE"}
_FALSE = {"F", "FALSE"}
PERCENT = ("precision", "recall", "f1")


def label(value: object) -> str:
    """``T``, ``F`` or :data:`~bpb_core.scored_units.INVALID` for an answer value."""
    if isinstance(value, bool):
        return "T" if value else "F"
    if isinstance(value, str):
        text = value.strip().upper()
        if text in _TRUE:
            return "T"
        if text in _FALSE:
            return "F"
    return INVALID


def collect(
    items: list[Mapping[str, Any]], key: str, known: set[str], parse_key: Any
) -> tuple[dict[str, Any], set[str]]:
    """Map unit name to its entry, for known units only; also return units seen twice."""
    found: dict[str, Any] = {}
    dups: set[str] = set()
    for item in items:
        parsed = parse_key(item.get(key))
        if parsed is None or str(parsed) not in known:
            continue
        name = str(parsed)
        if name in found:
            dups.add(name)
        found[name] = item
    return found, dups


class LabelScorer(ABC):
    """Shared units/score logic; subclasses say which entry key names a unit and the truth.

    Attributes:
        noun: How a unit is named in the gallery's text (``"ball "`` for ``ball 3``).
    """

    name: str
    task: str
    scene_rule: Literal["mean", "all"]
    key: str
    noun: str = ""
    columns: Mapping[str, str] = {}

    parse_key: Callable[[object], object]  # the unit an entry's key value names, or None

    @abstractmethod
    def labels(self, truth: FinalState) -> dict[str, str]:
        """Unit name to its true label."""

    def units(
        self, answer: Mapping[str, Any] | None, truth: FinalState, scene: Scene
    ) -> list[UnitRow]:
        labels = self.labels(truth)
        found, dups = collect(entries(answer, "answers"), self.key, set(labels), self.parse_key)
        return [
            UnitRow(
                unit=name,
                truth=value,
                pred=label(found[name].get("answer")) if name in found else None,
                duplicate=name in dups,
            )
            for name, value in labels.items()
        ]

    def score(self, units: pd.DataFrame) -> pd.DataFrame:
        """``correct`` where the call is ok, the unit appears once and its label equals the
        truth."""
        ok = (units["status"] == "ok").to_numpy(dtype=bool)
        same = (units["truth"] == units["pred"]).to_numpy(dtype=bool)
        dup = units["duplicate"].to_numpy(dtype=bool)
        correct = ok & same & ~dup
        distance = np.full(len(units), np.nan)
        return pd.DataFrame({"correct": correct, "distance": distance}, index=units.index)

    def explain(self, rows: pd.DataFrame) -> list[str]:
        """``ball 3: said F, truth T`` for each wrong unit."""
        wrong = rows[~rows["correct"].astype(bool)]
        lines = []
        for unit, pred, truth in zip(wrong["unit"], wrong["pred"], wrong["truth"], strict=True):
            said = f"said {pred}" if isinstance(pred, str) else "no answer"
            lines.append(f"{self.noun}{unit}: {said}, truth {truth}")
        return lines


def labelled(units: pd.DataFrame, tasks: tuple[str, ...]) -> pd.DataFrame:
    """Units of ``tasks`` that carry a usable T/F label from an ok answer."""
    frame = units[units["task"].isin(tasks)]
    valid = (frame["status"] == "ok") & ~frame["duplicate"] & frame["pred"].isin(["T", "F"])
    return frame[valid]


def outcomes(frame: pd.DataFrame) -> pd.DataFrame:
    """Columns ``tp, fp, fn, tn``: 1 where a labelled unit is that outcome, else 0."""
    truth, pred = frame["truth"] == "T", frame["pred"] == "T"
    flags = {"tp": truth & pred, "fp": ~truth & pred, "fn": truth & ~pred, "tn": ~truth & ~pred}
    return pd.DataFrame(flags).astype("int64")


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
    keyed = pd.concat([frame[[*RUN_COLUMNS, "task", "unit"]], outcomes(frame)], axis=1)
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
