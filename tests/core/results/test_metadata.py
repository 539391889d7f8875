"""Adapters' own measurements: numbers by their median, yes/no values by the share that holds,
texts by their count; a scene counts once however many answers (tasks, epochs) carry the measure,
with the mean of its answers' values."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd

from bpb_core import AdapterInfo, ModelRequest, ModelResponse, hookimpl
from bpb_core.registry import make_registry
from bpb_core.report.build import build_report
from bpb_core.results import load_results
from bpb_core.results.tables import metadata_by_horizon, metadata_table
from bpb_core.runner import RunOptions, run_eval


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
    assert table.loc["ok", "scenes"] == 4 and table.loc["ok", "mean"] == 0.75
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


class Drawing:
    """An adapter that measures each answer afresh: ``draw`` is 1 the first time a scene-task is
    asked and 2 the second (``--epochs 2``), ``first`` whether it was the first time; ``width``
    is the same on every answer of a scene. Its reply does not parse: the measurements count."""

    def __init__(self) -> None:
        self.asked: dict[str, int] = {}
        self.name = "drawing:x"

    async def complete(self, request: ModelRequest) -> ModelResponse:
        key = repr(request.messages)  # the same for a scene-task in every epoch
        self.asked[key] = draw = self.asked.get(key, 0) + 1
        metadata: dict[str, bool | float | str] = {"draw": draw, "first": draw == 1}
        return ModelResponse("no idea", metadata=metadata | {"width": 7.0})


class DrawingPlugin:
    @hookimpl
    def bpb_model_adapters(self) -> list[AdapterInfo]:
        make = lambda: lambda model, options: Drawing()  # noqa: E731
        return [AdapterInfo("drawing", make, "Measures each answer afresh", offline=True)]


def test_a_two_epoch_run_counts_each_scene_once_with_the_mean_of_its_answers(
    dataset: Path, tmp_path: Path
) -> None:
    # With --epochs 2 the answers of a scene measured differently per epoch each counted (n was
    # 6 for 3 scenes, max 2), while answers measured alike on the tasks of a scene counted once:
    # "n" was scenes or answers depending on the values.
    registry = make_registry([DrawingPlugin()])
    run_eval(dataset, "drawing:x", tmp_path / "run", RunOptions(epochs=2), registry=registry)
    table = build_report([tmp_path / "run"], registry=registry, n_boot=20).tables["metadata"]
    calls = load_results([tmp_path / "run"], registry=registry).calls
    assert len(calls) == 2 * 3 * 6  # 2 epochs of 3 tasks on 6 scenes, each with its measures
    for measure, mean in (("draw", 1.5), ("first", 0.5), ("width", 7.0)):
        rows = table[table["measure"] == measure]
        assert list(rows["horizon"]) == [1.0, 3.0]
        assert (rows["scenes"] == 3).all(), rows  # 3 scenes per horizon, each once
        assert (rows["mean"] == mean).all(), rows
    draw = table[table["measure"] == "draw"]
    assert (draw["median"] == 1.5).all() and (draw["max"] == 1.5).all()  # per-scene means
