"""The adapters' own measurements (``metadata`` of each answer), summarised per run and horizon.

An adapter may return named numbers, yes/no values or strings with a reply (an offline
adapter's error in reading its input, say). Core does not know what they mean: each numeric
measure gets its count, median, mean and maximum per (run, horizon); each yes/no measure (JSON
``true``/``false``) its count and the share that is true (``mean``; no median); each text measure
(a reason, a label) its count. A scene whose tasks carry identical measurements counts once.
"""

from __future__ import annotations

import json
import math
import statistics
from collections import defaultdict
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import pandas as pd

METADATA_COLUMNS: dict[str, str] = {
    "run": "str",
    "horizon": "float64",
    "measure": "str",
    "n": "int64",
    "median": "float64",
    "mean": "float64",
    "max": "float64",
}


def metadata_table(calls: pd.DataFrame) -> pd.DataFrame:
    """One row per (run, horizon, measure) found in ``calls["metadata"]``; empty (with the
    columns of :data:`METADATA_COLUMNS`) when no answer carries any."""
    import pandas as pd

    values: dict[tuple[str, float, str], list[float | str]] = defaultdict(list)
    seen: set[tuple[str, str, str]] = set()
    rows = calls.loc[calls["metadata"].notna(), ["run", "horizon", "scene_id", "metadata"]]
    for run, horizon, scene_id, text in rows.itertuples(index=False):
        if (str(run), str(scene_id), text) in seen:
            continue
        seen.add((str(run), str(scene_id), text))
        for name, value in json.loads(text).items():
            values[(str(run), float(horizon), str(name))].append(value)
    records = [_summary(key, found) for key, found in sorted(values.items())]
    frame = pd.DataFrame(records, columns=list(METADATA_COLUMNS))
    return frame.astype(METADATA_COLUMNS)


def _summary(key: tuple[str, float, str], found: list[float | str]) -> dict[str, object]:
    numbers = sorted(float(v) for v in found if isinstance(v, int | float) and math.isfinite(v))
    run, horizon, measure = key
    row: dict[str, object] = {"run": run, "horizon": horizon, "measure": measure, "n": len(found)}
    if found and all(isinstance(v, bool) for v in found):  # a yes/no: its share, no median
        row |= {"median": math.nan, "mean": statistics.fmean(numbers), "max": math.nan}
    elif len(numbers) == len(found) and numbers:
        middle, mean = statistics.median(numbers), statistics.fmean(numbers)
        row |= {"median": middle, "mean": mean, "max": numbers[-1]}
    else:
        row |= {"median": math.nan, "mean": math.nan, "max": math.nan}
    return row


def metadata_by_horizon(table: pd.DataFrame) -> pd.DataFrame:
    """:func:`metadata_table` as one row per (run, measure) and one column per horizon
    (``h1``...): the median of a numeric measure, the share of a yes/no one, the count of a text
    one (its ``statistic`` column says which), to read beside the accuracy by horizon."""
    import pandas as pd

    if table.empty:
        return pd.DataFrame(columns=["run", "measure", "statistic"])
    share = table["median"].isna() & table["mean"].notna()
    counted = table["n"].astype("float64")
    value = table["median"].where(table["median"].notna(), table["mean"].where(share, counted))
    statistic = pd.Series("count", index=table.index).mask(share, "share")
    frame = table.assign(
        value=value,
        statistic=statistic.mask(table["median"].notna(), "median"),
        column=[f"h{h:g}" for h in table["horizon"]],
    )
    wide = frame.pivot_table(
        index=["run", "measure", "statistic"], columns="column", values="value", sort=False
    )
    order = [f"h{h:g}" for h in sorted(table["horizon"].unique())]
    return wide[order].reset_index().rename_axis(columns=None)
