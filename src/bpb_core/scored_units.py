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
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, NamedTuple

from bpb_core.errors import PluginBug, blamed, named

NAN = math.nan
INVALID = "?"

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


SCENE_RULES = ("mean", "all")


def check_scorer(scorer: Any, origin: str) -> None:
    """Raise a :class:`PluginBug` naming ``origin`` and the attribute unless the scorer's
    ``scene_rule`` is one of :data:`SCENE_RULES` and its ``columns`` map column names to dtypes:
    any other rule would be scored as ``mean`` without a word, wrong columns fail deep in pandas.
    """
    what, rule = named("scorer", scorer), getattr(scorer, "scene_rule", None)
    if rule not in SCENE_RULES:
        raise PluginBug(f"{origin}: {what}: scene_rule is {rule!r}; expected 'mean' or 'all'")
    columns = getattr(scorer, "columns", None)
    if not isinstance(columns, Mapping) or not all(
        isinstance(column, str) and isinstance(dtype, str) for column, dtype in columns.items()
    ):
        shown = repr(columns) if len(repr(columns)) <= 60 else type(columns).__name__
        raise PluginBug(
            f"{origin}: {what}: columns is {shown}; expected a dict of column name "
            "(str) -> pandas dtype (str)"
        )


def unit_rows(scorer: Any, origin: str, answer: Any, truth: Any, scene: Any) -> list[UnitRow]:
    """``scorer.units(answer, truth, scene)``, checked: a list of :class:`UnitRow` with one
    value per declared column (else a :class:`PluginBug` naming ``origin``, as for a raise)."""
    what = f"{named('scorer', scorer)}: units()"
    with blamed(origin, what):
        rows = scorer.units(answer, truth, scene)
    width = len(scorer.columns)
    if isinstance(rows, list | tuple) and all(
        isinstance(row, UnitRow) and len(row.values) == width for row in rows
    ):
        return list(rows)
    shown = repr(rows)
    shown = shown if len(shown) <= 80 else shown[:77] + "..."
    raise PluginBug(
        f"{origin}: {what} returned {shown}; expected a list of "
        f"bpb_core.UnitRow, each with {width} values (one per declared column)"
    )


def scored_units(scorer: Any, origin: str, frame: Any) -> Any:
    """``scorer.score(frame)``, checked: a frame with ``correct`` and ``distance`` and one row
    per row of ``frame``, on its index (else a :class:`PluginBug` naming ``origin``)."""
    import pandas as pd

    what = f"{named('scorer', scorer)}: score()"
    with blamed(origin, what):
        scored = scorer.score(frame)
    fits = isinstance(scored, pd.DataFrame) and set(SCORER_OUTPUT) <= set(scored.columns)
    if fits and len(scored) == len(frame) and scored.index.equals(frame.index):
        return scored
    got = type(scored).__name__
    if isinstance(scored, pd.DataFrame):
        got = f"a DataFrame with columns {list(scored.columns)} and {len(scored)} rows"
    raise PluginBug(
        f"{origin}: {what} returned {got}; expected a DataFrame with the "
        f"columns correct and distance, on the index of its input ({len(frame)} rows)"
    )


def input_frame(scorer: Any, calls: Iterable[tuple[str, Sequence[UnitRow]]]) -> Any:
    """The typed ``Scorer.score`` input for units already cut (:func:`unit_rows`): one
    ``(status, rows)`` per call; columns :data:`SCORER_INPUT` and the scorer's own."""
    import pandas as pd

    columns: dict[str, list[Any]] = {name: [] for name in (*SCORER_INPUT, *scorer.columns)}
    for status, rows in calls:
        columns["status"] += [status] * len(rows)
        for position, name in enumerate(("unit", "truth", "pred", "duplicate")):
            columns[name] += [row[position] for row in rows]
        for position, name in enumerate(scorer.columns):
            columns[name] += [row.values[position] for row in rows]
    dtypes = {**SCORER_INPUT, **scorer.columns}
    return pd.DataFrame({name: pd.Series(v, dtype=dtypes[name]) for name, v in columns.items()})


def object_origin(component: object) -> str:
    """Who to blame for a component handed over as an object rather than registered: its
    module (``module 'my_scorers'``)."""
    return f"module {type(component).__module__!r}"
