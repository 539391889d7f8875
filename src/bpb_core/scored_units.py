"""Scored units: the rows a :class:`~bpb_core.interfaces.Scorer` turns answers into.

A *unit* is the smallest thing that is right or wrong: one labelled object, one yes/no item, one
predicted position. A scorer first cuts every answer into :class:`UnitRow` values
(``Scorer.units``), :func:`bpb_core.results.load_results` stacks them for all runs, scenes and
tasks into one pandas frame, and ``Scorer.score`` then marks each task's rows at once,
vectorised.

Columns every scorer may read in ``score`` (see :data:`SCORER_INPUT`):

========== ========= ==============================================================
column     dtype     meaning
========== ========= ==============================================================
status     category  ``ok``, ``parse_error``, ``api_error`` or ``missing`` (no file)
unit       str       what the unit is (an id such as ``"3"``, a name such as ``"TOP"``)
truth      str       the true label
pred       str       the predicted label; NaN when the answer does not mention the
                     unit, :data:`INVALID` when it mentions it with an unusable value
duplicate  bool      the answer mentions the unit more than once
========== ========= ==============================================================

A scorer adds its own columns (``Scorer.columns``: name to dtype), filled from
:attr:`UnitRow.values`; rows of other tasks hold NaN there.
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
}
"""Columns given to every ``Scorer.score`` and their pandas dtypes."""

SCORER_OUTPUT: dict[str, str] = {"correct": "bool", "distance": "float64"}
"""Columns ``Scorer.score`` returns (same index as its input)."""


class UnitRow(NamedTuple):
    """One scored unit of one answer, before scoring (see the module docstring).

    Attributes:
        values: The scorer's own columns, in the order of ``Scorer.columns``.
    """

    unit: str
    truth: str | None
    pred: str | None
    duplicate: bool = False
    values: tuple[Any, ...] = ()


def entries(answer: Mapping[str, Any] | None, key: str) -> list[Mapping[str, Any]]:
    """The list of dict entries under ``answer[key]``; anything else is skipped."""
    if not isinstance(answer, Mapping):
        return []
    items = answer.get(key)
    if not isinstance(items, list):
        return []
    return [item for item in items if isinstance(item, Mapping)]
