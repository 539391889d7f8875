"""Scorers for yes/no labels: Q1 (did the cue ball touch ball i?) and Q2 (did it touch wall w?).

Rules, applied per unit (object ball or wall):

- A label is ``T`` or ``F``; case and surrounding spaces are ignored, ``TRUE``/``FALSE`` and JSON
  booleans are read as ``T``/``F``. Any other value is an invalid label and is wrong.
- A unit the answer does not mention is wrong; a unit mentioned twice or more is wrong, even when
  the copies agree (the answer is ambiguous).
- Entries for units the truth does not have (ball 0 or 7 in Q1, a ``MIDDLE`` wall) and extra keys
  inside an entry are ignored.
- Only answers with status ``ok`` can be right.

Q1 scores a scene by the share of its object balls that are right (per-ball accuracy); Q2 gives a
scene 1 only when all four walls are right (exact wall-set match).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from typing import Any, Literal

import numpy as np
import pandas as pd

from bpb_core.scene import FinalState, Scene
from bpb_core.units import INVALID, UnitRow, entries

_TRUE = {"T", "TRUE"}
_FALSE = {"F", "FALSE"}
_WALL_NAMES = {"TOP", "BOTTOM", "LEFT", "RIGHT"}


def label(value: object) -> str:
    """``T``, ``F`` or :data:`~bpb_core.units.INVALID` for an answer value."""
    if isinstance(value, bool):
        return "T" if value else "F"
    if isinstance(value, str):
        text = value.strip().upper()
        if text in _TRUE:
            return "T"
        if text in _FALSE:
            return "F"
    return INVALID


def ball_id(value: object) -> int | None:
    """An integer ball id from ``3`` or ``"3"``; ``None`` for anything else."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int):
        return value
    if isinstance(value, float) and value.is_integer():
        return int(value)
    if isinstance(value, str) and value.strip().isdigit():
        return int(value.strip())
    return None


def wall_name(value: object) -> str | None:
    """An upper-case wall name, or ``None`` when ``value`` names no wall."""
    if isinstance(value, str) and value.strip().upper() in _WALL_NAMES:
        return value.strip().upper()
    return None


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


class _LabelScorer(ABC):
    """Shared units/score logic; subclasses say which entry key names a unit and the truth."""

    name: str
    task: str
    scene_rule: Literal["mean", "all"]
    key: str

    parse_key: Callable[[object], object]  # the unit an entry's key value names, or None

    @abstractmethod
    def truth(self, final: FinalState) -> dict[str, str]:
        """Unit name to its true label."""

    def units(
        self, answer: Mapping[str, Any] | None, final: FinalState, scene: Scene
    ) -> list[UnitRow]:
        truth = self.truth(final)
        found, dups = collect(entries(answer, "answers"), self.key, set(truth), self.parse_key)
        return [
            UnitRow(
                unit=name,
                truth=value,
                pred=label(found[name].get("answer")) if name in found else None,
                duplicate=name in dups,
            )
            for name, value in truth.items()
        ]

    def score(self, units: pd.DataFrame) -> pd.DataFrame:
        return score_labels(units)


class Q1Scorer(_LabelScorer):
    """Q1: per-ball accuracy over the object balls (see the module docstring for the rules)."""

    name = "q1"
    task = "q1"
    scene_rule: Literal["mean", "all"] = "mean"
    key = "id"
    parse_key = staticmethod(ball_id)

    def truth(self, final: FinalState) -> dict[str, str]:
        return {str(t.id): t.answer for t in final.q1}


class Q2Scorer(_LabelScorer):
    """Q2: exact wall-set match per scene; each wall is also a unit for the confusion tables."""

    name = "q2"
    task = "q2"
    scene_rule: Literal["mean", "all"] = "all"
    key = "wall"
    parse_key = staticmethod(wall_name)

    def truth(self, final: FinalState) -> dict[str, str]:
        return {t.wall: t.answer for t in final.q2}
