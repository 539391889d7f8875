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
rule of :mod:`bpb_tasks.questions.ids`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from typing import Any, Literal

import numpy as np
import pandas as pd

from bpb_core.scored_units import INVALID, UnitRow, entries
from bpb_tasks.billiards.scene import Scene
from bpb_tasks.billiards.truth import FinalState

_TRUE = {"T", "TRUE"}
_FALSE = {"F", "FALSE"}


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


def score_labels(units: pd.DataFrame) -> pd.DataFrame:
    """``correct`` where the call is ok, the unit appears once and its label equals the truth."""
    ok = (units["status"] == "ok").to_numpy(dtype=bool)
    same = (units["truth"] == units["pred"]).to_numpy(dtype=bool)
    dup = units["duplicate"].to_numpy(dtype=bool)
    correct = ok & same & ~dup
    distance = np.full(len(units), np.nan)
    return pd.DataFrame({"correct": correct, "distance": distance}, index=units.index)


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
        return score_labels(units)

    def explain(self, rows: pd.DataFrame) -> list[str]:
        """``ball 3: said F, truth T`` for each wrong unit."""
        wrong = rows[~rows["correct"].astype(bool)]
        lines = []
        for unit, pred, truth in zip(wrong["unit"], wrong["pred"], wrong["truth"], strict=True):
            said = f"said {pred}" if isinstance(pred, str) else "no answer"
            lines.append(f"{self.noun}{unit}: {said}, truth {truth}")
        return lines
