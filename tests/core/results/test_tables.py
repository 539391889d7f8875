"""Accuracy tables and leaderboards of the hand-made runs, checked against hand-worked numbers."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bpb_core.errors import BadInput
from bpb_core.results import CALL_DTYPES, META_DTYPES, load_results, summary
from bpb_core.results.reading import StrayAnswerWarning
from bpb_core.results.tables import accuracy, by_horizon, leaderboard
from bpb_core.scored_units import SCORER_INPUT, SCORER_OUTPUT
from bpb_tasks.q3.scorer import COLUMNS as Q3_COLUMNS


def board(runs: Path, **kwargs: object) -> pd.DataFrame:
    results = load_results(runs)
    return leaderboard(results.units, results.suites, **kwargs).set_index("run")  # type: ignore[arg-type]


def test_frames_have_the_documented_dtypes(runs: Path) -> None:
    res = load_results(runs)
    # base columns, then each scorer's own (q3's positions), then the scorer output
    expected = {**META_DTYPES, **SCORER_INPUT, **Q3_COLUMNS, **SCORER_OUTPUT}
    assert {k: str(v) for k, v in res.units.dtypes.items()} == expected
    assert list(res.units.columns) == list(expected)
    assert {k: str(v) for k, v in res.calls.dtypes.items()} == CALL_DTYPES
    assert res.units.loc[res.units["task"] == "q1", "truth_x"].isna().all()
    assert [s.name for s in res.suites] == ["total"]
    # 3 runs x 4 scenes x (6 + 4 + 7) units; 3 runs x 4 scenes x 3 tasks calls
    assert len(res.units) == 3 * 4 * 17 and len(res.calls) == 3 * 4 * 3


def test_oracle_scores_100_percent_everywhere(runs: Path) -> None:
    row = board(runs).loc["baseline_oracle"]
    assert row[["q1", "q2", "q3", "total"]].tolist() == [1.0, 1.0, 1.0, 1.0]
    assert row["completeness"] == 1.0 and bool(row["baseline"])


def test_stasis_scores_match_the_hand_worked_numbers(runs: Path) -> None:
    units = load_results(runs).units
    wide = by_horizon(units).set_index(["run", "task"]).loc["baseline_stasis"]
    # Q1: h1 (5/6 + 6/6)/2, h2 (4/6 + 6/6)/2; Q2: one wall-free scene per horizon;
    # Q3: h1 (5/7 + 6/7)/2, h2 (4/7 + 6/7)/2 (ball 3's 0.01 m move is within R)
    assert wide.loc["q1", ["h1", "h2"]].tolist() == pytest.approx([11 / 12, 10 / 12])
    assert wide.loc["q2", ["h1", "h2"]].tolist() == [0.5, 0.5]
    assert wide.loc["q3", ["h1", "h2"]].tolist() == pytest.approx([11 / 14, 10 / 14])
    row = board(runs).loc["baseline_stasis"]
    assert row["q1"] == pytest.approx(0.875) and row["q3"] == pytest.approx(0.75)
    assert row["total"] == pytest.approx(0.3 * 0.875 + 0.3 * 0.5 + 0.4 * 0.75)


def test_strict_and_answered_views_and_completeness(runs: Path) -> None:
    strict = board(runs, include_incomplete=True).loc["litellm_model"]
    answered = board(runs, view="answered", include_incomplete=True).loc["litellm_model"]
    assert strict[["q1", "q2", "q3"]].tolist() == pytest.approx([0.5, 0.5, 5 / 7])
    # answered: q1 drops the api_error and the missing scene; the parse error stays wrong
    assert answered[["q1", "q2", "q3"]].tolist() == pytest.approx([1.0, 0.75, 27 / 28])
    assert strict["completeness"] == pytest.approx(8 / 12)
    acc = accuracy(load_results(runs).units).set_index(["run", "task", "horizon"])
    assert acc.loc[("litellm_model", "q1", 1.0), "completeness"] == 0.5


def test_a_task_with_a_cell_under_the_threshold_is_left_out_of_the_leaderboard(
    runs: Path,
) -> None:
    # every task of the model has a horizon half answered (h2_0000 has no files at all)
    row = board(runs, view="answered").loc["litellm_model"]
    assert row[["q1", "q2", "q3", "total"]].isna().all()
    assert row["short"] == "q1, q2, q3" and row["worst_cell"] == 0.5
    assert board(runs).index[-1] == "litellm_model"  # NaN ranks last, never above a floor
    # a lower threshold keeps q2 and q3 (one cell each at 50%) ... and q1 (h1 and h2 at 50%)
    kept = board(runs, view="answered", min_complete=0.5).loc["litellm_model"]
    assert kept[["q1", "q2", "q3"]].tolist() == pytest.approx([1.0, 0.75, 27 / 28])
    assert kept["short"] == ""
    assert board(runs).loc["baseline_oracle", "short"] == ""
    wide = by_horizon(load_results(runs).units, view="answered").set_index(["run", "task"])
    model = wide.loc[("litellm_model", "q2")]
    assert (model["h1"], model["h1_complete"], model["h2_complete"]) == (0.5, 1.0, 0.5)
    assert np.isnan(model["mean"])  # a mean over the answered horizon only would mislead
    assert wide.loc[("baseline_stasis", "q2"), "mean"] == 0.5


def test_stable_subset_drops_unstable_scenes(runs: Path) -> None:
    row = board(runs, stable_only=True).loc["baseline_stasis"]
    assert row["q1"] == pytest.approx((11 / 12 + 1.0) / 2)  # h2 keeps only h2_0001


def test_summary_lists_best_first_with_answered_total(runs: Path) -> None:
    results = load_results(runs)
    table = summary(results.units, results.suites, include_incomplete=True)
    assert table["run"].tolist() == ["baseline_oracle", "baseline_stasis", "litellm_model"]
    model = table.set_index("run").loc["litellm_model"]
    assert model["total_answered"] == pytest.approx(0.3 + 0.3 * 0.75 + 0.4 * 27 / 28)


def test_bad_run_folders_are_reported_by_file(tmp_path: Path, runs: Path) -> None:
    with pytest.raises(BadInput, match="no such run folder"):
        load_results(tmp_path / "nope")
    (runs / "litellm_model" / "h1" / "scene_0000" / "q1.json").write_text("{not json")
    with pytest.raises(BadInput, match=r"q1\.json: not an answer file: Invalid JSON"):
        load_results(runs)


def test_relative_dataset_path_is_resolved_from_the_run_folder(runs: Path) -> None:
    manifest = runs / "baseline_oracle" / "run.json"
    manifest.write_text(manifest.read_text().replace(str(runs.parent / "data"), "../../data"))
    assert board(runs / "baseline_oracle").loc["baseline_oracle", "total"] == 1.0


def test_without_a_suite_there_is_no_total_and_tasks_rank_by_their_mean(runs: Path) -> None:
    units = load_results(runs).units
    table = leaderboard(units)
    assert "total" not in table.columns
    assert list(table.columns[4:7]) == ["q1", "q2", "q3"]
    assert table["run"].tolist()[0] == "baseline_oracle"


def _select(runs: Path, **options: object) -> None:
    manifest = runs / "litellm_model" / "run.json"
    data = json.loads(manifest.read_text())
    data["options"] = options
    manifest.write_text(json.dumps(data))


def test_run_options_select_the_scenes_expected(runs: Path) -> None:
    # the answers of the scenes the edited run.json no longer selects are left out, said so
    _select(runs, horizons=[1.0])
    with pytest.warns(StrayAnswerWarning, match="3 answer files outside the run's selection"):
        calls = load_results(runs / "litellm_model").calls
    assert sorted(set(calls["scene_id"])) == ["h1_0000", "h1_0001"]
    _select(runs, horizons=None, limit=1)
    with pytest.warns(StrayAnswerWarning, match=r"6 answer files .*h1/scene_0001/q1\.json"):
        calls = load_results(runs / "litellm_model").calls
    assert sorted(set(calls["scene_id"])) == ["h1_0000", "h2_0000"]
    # h2_0000 has no answer files: expected, so it counts as missing, not as absent
    missing = calls[calls["scene_id"] == "h2_0000"]["status"]
    assert set(missing) == {"missing"}
    with pytest.warns(StrayAnswerWarning):
        assert board(runs / "litellm_model").loc["litellm_model", "completeness"] == 0.5


def test_a_run_on_a_dataset_regenerated_since_is_refused(runs: Path) -> None:
    data = runs.parent / "data"
    (data / "dataset.json").write_text(json.dumps({"name": "hand-made", "dataset_hash": "a" * 64}))
    manifest = runs / "litellm_model" / "run.json"
    record = json.loads(manifest.read_text())
    manifest.write_text(json.dumps({**record, "dataset_hash": "a" * 64}))
    assert len(load_results(runs / "litellm_model").calls) == 12  # the same dataset: fine
    manifest.write_text(json.dumps({**record, "dataset_hash": "b" * 64}))
    with pytest.raises(BadInput, match=r"run\.json: dataset_hash bbbbbbbbbbbb but .* aaaaaaaaaaaa"):
        load_results(runs / "litellm_model")


@pytest.mark.parametrize("cost", [float("nan"), float("inf"), -0.5])
def test_answer_file_with_a_cost_that_is_no_amount_is_refused(runs: Path, cost: float) -> None:
    # Summed silently, a NaN cost made the run's cost NaN and a negative one lowered it.
    answer = runs / "litellm_model" / "h1" / "scene_0000" / "q1.json"
    data = json.loads(answer.read_text())
    answer.write_text(json.dumps({**data, "cost": cost}))  # written as NaN, Infinity, -0.5
    with pytest.raises(BadInput, match=r"q1\.json: not an answer file: cost: ") as caught:
        load_results(runs)
    assert "\n" not in str(caught.value)
