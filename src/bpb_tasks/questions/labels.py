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

Q1 scores a scene by the share of its object balls that are right (per-ball accuracy,
:class:`Q1Scorer`); Q2 gives a scene 1 only when all four walls are right (exact wall-set match,
:class:`Q2Scorer`). Keys are read with the one
rule of :mod:`bpb_tasks.questions.answers`.

Most object balls are not touched by the cue ball, so Q1's per-ball accuracy rewards answering
``F`` for every ball: the do-nothing ``stasis`` baseline gets about 90% on the paper's setting.
The metrics reports show beside it (:func:`q1_metrics`) are not dominated by the ``F`` class:

- ``exact_set``: share of scenes with every object ball right (the set of balls hit);
- ``recall``, ``precision``, ``f1``: of contacts (positive = ``T``), pooled over answered units;
- ``balanced_accuracy``: mean of recall and specificity. It is the chance-corrected one: any
  answer that ignores the scene (always ``F``, always ``T``, coin flips) scores 50% in
  expectation, whatever the share of contacts.

Scene metrics (``per_ball``, ``exact_set``) are means over scenes per horizon, then over
horizons, like the leaderboard; label metrics pool the labelled units (``ok`` answers with a
valid, unduplicated ``T``/``F``) over all horizons.

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
from bpb_tasks.questions.answers import ball_id, wall_name

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


METRIC_NOTES: dict[str, str] = {
    "per_ball": "the paper's metric: share of object balls labelled right; favours 'no "
    "collision', since most balls are not hit (stasis, all F, scores high)",
    "exact_set": "share of scenes with every object ball right (the whole set of balls hit)",
    "recall": "share of true contacts labelled T (stasis: 0%)",
    "precision": "share of T labels that are true contacts",
    "f1": "harmonic mean of precision and recall (0% for an answer that never says T)",
    "balanced_accuracy": "mean of recall and specificity; chance-corrected: any answer that "
    "ignores the scene scores 50%",
}
COUNTS = ("tp", "fp", "fn", "tn")


class Q1Scorer(LabelScorer):
    """One unit per object ball; a scene scores the share of its balls that are right."""

    name = "q1"
    task = "q1"
    scene_rule: Literal["mean", "all"] = "mean"
    key = "id"
    noun = "ball "
    parse_key = staticmethod(ball_id)
    metric_notes = METRIC_NOTES

    def task_metrics(self, units: pd.DataFrame) -> pd.DataFrame:
        """Per-ball and exact-set accuracy, recall, precision, F1, balanced accuracy per run."""
        return q1_metrics(units)

    def labels(self, truth: FinalState) -> dict[str, str]:
        return {str(t.id): t.answer for t in truth.q1}


class Q1Confusion(ConfusionDiagnostic):
    """Q1 confusion over all object balls: tp, fp, fn, tn, precision, recall, F1 per run."""

    name = "q1_confusion"
    title = "Q1 confusion (all object balls; answered units)"
    task = "q1"


def q1_metrics(units: pd.DataFrame) -> pd.DataFrame:
    """Every Q1 metric per run of ``units`` (Q1 units of answered calls), run columns first,
    then :data:`METRIC_NOTES`' columns, then the confusion counts: ``per_ball`` and
    ``exact_set`` are means over scenes then over horizons, the confusion counts, recall,
    precision, F1 and balanced accuracy pool the labelled units."""
    if units.empty:
        return pd.DataFrame(columns=[*RUN_COLUMNS, *METRIC_NOTES, *COUNTS])
    grouped = units.groupby([*RUN_COLUMNS, "horizon", "index"], observed=True)["correct"]
    scenes = pd.DataFrame({"per_ball": grouped.mean(), "exact_set": grouped.all()})
    scenes = scenes.astype("float64").reset_index()
    columns = ["per_ball", "exact_set"]
    by_horizon = scenes.groupby([*RUN_COLUMNS, "horizon"], observed=True)[columns].mean()
    frame = labelled(units, ("q1",))
    counts = pd.concat([frame[RUN_COLUMNS], outcomes(frame)], axis=1)
    out = rates(counts.groupby(RUN_COLUMNS, observed=True)[list(COUNTS)].sum())
    tp, wrong = out["tp"], out["fp"] + out["fn"]
    out["f1"] = (2 * tp / (2 * tp + wrong).where(2 * tp + wrong > 0)).astype("float64")
    negatives = (out["tn"] + out["fp"]).where(out["tn"] + out["fp"] > 0)
    specificity = out["tn"] / negatives
    out["balanced_accuracy"] = (out["recall"] + specificity) / 2
    both = by_horizon.groupby(level=RUN_COLUMNS, observed=True)[columns].mean()
    both = both.join(out, how="left")
    both[list(COUNTS)] = both[list(COUNTS)].fillna(0).astype("int64")
    both = both.reset_index()[[*RUN_COLUMNS, *METRIC_NOTES, *COUNTS]]
    return both.astype({name: np.float64 for name in METRIC_NOTES})


class Q2Scorer(LabelScorer):
    """One unit per wall (for the per-wall confusion); a scene scores 1 only when all four are
    right."""

    name = "q2"
    task = "q2"
    scene_rule: Literal["mean", "all"] = "all"
    key = "wall"
    parse_key = staticmethod(wall_name)

    def labels(self, truth: FinalState) -> dict[str, str]:
        return {t.wall: t.answer for t in truth.q2}


class Q2Confusion(ConfusionDiagnostic):
    """Q2 confusion pooled over the walls (``all``) and per wall, per run."""

    name = "q2_confusion"
    title = "Q2 confusion (all walls and per wall; answered units)"
    task = "q2"
    per_unit = True
