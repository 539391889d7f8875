"""The adapters' own measurements (``metadata`` of each answer), summarised per run and horizon.

An adapter may return named numbers, yes/no values or strings with a reply (an offline
adapter's error in reading its input, say). Core does not know what they mean: each numeric
measure gets its count of scenes, median, mean and maximum per (run, horizon); each yes/no
measure (JSON ``true``/``false``) its count of scenes and the share that is true (``mean``; no
median); each text measure (a reason, a label) its count of scenes.

Everything is per scene, however many answers it has (one per task, again per ``--epochs``):
``scenes`` counts the scenes whose answers carry the measure, each once, and a scene's value is
the mean over its answers (the share of them that hold, for a yes/no measure); median, mean and
maximum are taken over those per-scene values.
"""

from __future__ import annotations

import json
import math
import statistics
from collections import defaultdict
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import pandas as pd

Value = bool | float | str  # one measurement as an answer file holds it (JSON)

METADATA_COLUMNS: dict[str, str] = {
    "run": "str",
    "horizon": "float64",
    "measure": "str",
    "scenes": "int64",
    "median": "float64",
    "mean": "float64",
    "max": "float64",
}


def metadata_table(calls: pd.DataFrame) -> pd.DataFrame:
    """One row per (run, horizon, measure) found in ``calls["metadata"]``; empty (with the
    columns of :data:`METADATA_COLUMNS`) when no answer carries any."""
    import pandas as pd

    values: dict[tuple[str, float, str], dict[str, list[Value]]] = defaultdict(
        lambda: defaultdict(list)
    )
    parsed: dict[str, dict[str, Value]] = {}  # the tasks of a scene often carry the same text
    rows = calls.loc[calls["metadata"].notna(), ["run", "horizon", "scene_id", "metadata"]]
    for run, horizon, scene_id, text in rows.itertuples(index=False):
        if text not in parsed:
            parsed[text] = json.loads(text)
        for name, value in parsed[text].items():
            values[(str(run), float(horizon), str(name))][str(scene_id)].append(value)
    records = [_summary(key, by_scene) for key, by_scene in sorted(values.items())]
    frame = pd.DataFrame(records, columns=list(METADATA_COLUMNS))
    return frame.astype(METADATA_COLUMNS)


def _summary(key: tuple[str, float, str], by_scene: dict[str, list[Value]]) -> dict[str, object]:
    """One measure's row: each scene once, its value the mean over its answers."""
    run, horizon, measure = key
    row: dict[str, object] = {"run": run, "horizon": horizon, "measure": measure}
    row["scenes"] = len(by_scene)
    found = [v for answers in by_scene.values() for v in answers]
    numeric = all(isinstance(v, int | float) and math.isfinite(v) for v in found)
    if not numeric:  # a text (or a mix with one): only counted
        return row | {"median": math.nan, "mean": math.nan, "max": math.nan}
    scenes = sorted(statistics.fmean(map(float, answers)) for answers in by_scene.values())
    if all(isinstance(v, bool) for v in found):  # a yes/no: its share, no median
        return row | {"median": math.nan, "mean": statistics.fmean(scenes), "max": math.nan}
    middle, mean = statistics.median(scenes), statistics.fmean(scenes)
    return row | {"median": middle, "mean": mean, "max": scenes[-1]}


def metadata_by_horizon(table: pd.DataFrame) -> pd.DataFrame:
    """:func:`metadata_table` as one row per (run, measure) and one column per horizon
    (``h1``...): the median of a numeric measure, the share of a yes/no one, the count of a text
    one (its ``statistic`` column says which), to read beside the accuracy by horizon."""
    import pandas as pd

    if table.empty:
        return pd.DataFrame(columns=["run", "measure", "statistic"])
    share = table["median"].isna() & table["mean"].notna()
    counted = table["scenes"].astype("float64")
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
