"""Scored units: the rows a :class:`~bpb_core.interfaces.Scorer` turns answers into.

A *unit* is the smallest thing that is right or wrong: one object ball in Q1, one wall in Q2, one
ball position in Q3. A scorer first cuts every answer into :class:`UnitRow` values
(``Scorer.units``), :func:`bpb_core.results.load_frame` stacks them for all runs, scenes and tasks
into one pandas frame, and ``Scorer.score`` then marks the whole frame at once, vectorised.

Columns a scorer may read in ``score`` (see :data:`SCORER_INPUT`):

========== ========= ==============================================================
column     dtype     meaning
========== ========= ==============================================================
status     category  ``ok``, ``parse_error``, ``api_error`` or ``missing`` (no file)
unit       str       ball id (``"3"``) or wall (``"TOP"``)
truth      str       true label: ``T``/``F`` (Q1, Q2); ``pos``/``null`` (Q3)
pred       str       predicted label; NaN when the answer does not mention the unit,
                     ``?`` when it mentions it with a value that is not a label
duplicate  bool      the answer mentions the unit more than once
truth_x/y  float64   true position (Q3; NaN when pocketed or not a position task)
pred_x/y   float64   predicted position (Q3; NaN when null, missing or invalid)
start_x/y  float64   the ball's position at t = 0 (Q3)
radius     float64   ball radius of the scene (m)
========== ========= ==============================================================
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, NamedTuple

NAN = math.nan
INVALID = "?"
STATUSES = ("ok", "parse_error", "api_error", "missing")

SCORER_INPUT: dict[str, str] = {
    "status": "category",
    "unit": "str",
    "truth": "str",
    "pred": "str",
    "duplicate": "bool",
    "truth_x": "float64",
    "truth_y": "float64",
    "pred_x": "float64",
    "pred_y": "float64",
    "start_x": "float64",
    "start_y": "float64",
    "radius": "float64",
}
"""Columns given to ``Scorer.score`` and their pandas dtypes."""

SCORER_OUTPUT: dict[str, str] = {"correct": "bool", "distance": "float64"}
"""Columns ``Scorer.score`` returns (same index as its input)."""


class UnitRow(NamedTuple):
    """One scored unit of one answer, before scoring (see the module docstring)."""

    unit: str
    truth: str | None
    pred: str | None
    duplicate: bool = False
    truth_x: float = NAN
    truth_y: float = NAN
    pred_x: float = NAN
    pred_y: float = NAN
    start_x: float = NAN
    start_y: float = NAN
    radius: float = NAN


def entries(answer: Mapping[str, Any] | None, key: str) -> list[Mapping[str, Any]]:
    """The list of dict entries under ``answer[key]``; anything else is skipped."""
    if not isinstance(answer, Mapping):
        return []
    items = answer.get(key)
    if not isinstance(items, list):
        return []
    return [item for item in items if isinstance(item, Mapping)]
