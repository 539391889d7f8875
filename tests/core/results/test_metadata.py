"""Adapters' own measurements: numbers by their median, yes/no values by the share that holds,
texts by their count; a scene counts once however many of its tasks carry the same values."""

from __future__ import annotations

import json
import math

import pandas as pd

from bpb_core.results.metadata import metadata_by_horizon, metadata_table


def _calls(rows: list[tuple[str, float, str, dict[str, object]]]) -> pd.DataFrame:
    return pd.DataFrame(
        [(run, h, scene, json.dumps(meta)) for run, h, scene, meta in rows],
        columns=["run", "horizon", "scene_id", "metadata"],
    )


def test_yes_no_measures_show_their_share_and_numbers_their_median() -> None:
    rows = []
    for i, (ok, error) in enumerate([(True, 1.0), (True, 3.0), (False, 2.0), (True, 10.0)]):
        for _task in ("a", "b"):  # the same values on each task of a scene: counted once
            rows.append(("r", 1.0, f"s{i}", {"ok": ok, "error": error}))
    rows.append(("r", 1.0, "s9", {"why": "unreadable"}))
    table = metadata_table(_calls(rows)).set_index("measure")
    assert table.loc["ok", "n"] == 4 and table.loc["ok", "mean"] == 0.75
    assert math.isnan(table.loc["ok", "median"])  # a median of yes/no says nothing
    assert table.loc["error", "median"] == 2.5 and table.loc["error", "max"] == 10.0
    wide = metadata_by_horizon(table.reset_index()).set_index("measure")
    assert wide.loc["ok", "statistic"] == "share" and wide.loc["ok", "h1"] == 0.75
    assert wide.loc["error", "statistic"] == "median" and wide.loc["error", "h1"] == 2.5
    assert wide.loc["why", "statistic"] == "count" and wide.loc["why", "h1"] == 1


def test_a_measure_mixing_yes_no_and_numbers_is_not_a_share() -> None:
    rows = [("r", 2.0, "s0", {"m": True}), ("r", 2.0, "s1", {"m": 0.5})]
    wide = metadata_by_horizon(metadata_table(_calls(rows))).set_index("measure")
    assert wide.loc["m", "statistic"] == "median"
