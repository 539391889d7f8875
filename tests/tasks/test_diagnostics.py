"""The billiards questions' diagnostics on the hand-made runs (numbers worked out in
support/reports_fixture): confusion, stasis index, Q3 distance errors and tolerance curve."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bpb_core.registry import Registry
from bpb_core.results import load_results
from bpb_tasks.paper.stasis import stasis_index
from bpb_tasks.q3.scorer import distance_errors, tolerance_curve
from bpb_tasks.questions.labels import confusion


@pytest.fixture
def units(runs: Path, registry: Registry) -> pd.DataFrame:
    return load_results(runs, registry=registry).units


def test_stasis_index_of_the_stasis_baseline_is_one_and_counts_match(units: pd.DataFrame) -> None:
    table = stasis_index(units).set_index("run")
    stasis = table.loc["baseline_stasis"]
    assert (
        stasis[["contact_stasis", "q1_stasis", "q2_stasis", "motion_stasis"]].tolist() == [1.0] * 4
    )
    # true contacts: Q1 {1}, {1,2}; Q2 {TOP}, {LEFT,TOP}; moved: 2 + 1 + 3 (one pocketed) + 1
    assert (stasis["contacts"], stasis["moved"]) == (6, 7)
    oracle = table.loc["baseline_oracle"]
    assert oracle["contact_stasis"] == 0.0 and oracle["motion_stasis"] == 0.0
    model = table.loc["litellm_model"]
    # answered contacts: only h1_0000's ball 1 (right); moved answered: 4, one predicted still
    assert (model["contacts"], model["moved"], model["motion_stasis"]) == (1, 4, 0.25)
    assert np.isnan(model["q2_stasis"])


def test_confusion_per_wall_and_pooled(units: pd.DataFrame) -> None:
    both = pd.concat(
        [confusion(units, "q1", per_unit=False), confusion(units, "q2", per_unit=True)]
    )
    table = both.set_index(["run", "task", "unit"])
    top = table.loc[("baseline_stasis", "q2", "TOP")]
    assert top[["tp", "fp", "fn", "tn"]].tolist() == [0, 0, 2, 2]
    assert top["recall"] == 0.0 and np.isnan(top["precision"])
    q1 = table.loc[("baseline_oracle", "q1", "all")]
    assert q1[["tp", "fp", "fn", "tn", "f1"]].tolist() == [3, 0, 0, 21, 1.0]


def test_distance_errors_and_tolerance_curve(units: pd.DataFrame) -> None:
    errors = distance_errors(units).set_index("run")
    assert errors.loc["baseline_oracle", "mean"] == 0.0
    assert errors.loc["baseline_stasis", "null_mismatch"] == 1  # the pocketed ball
    curve = tolerance_curve(units)
    stasis = curve[curve["run"] == "baseline_stasis"].set_index("tolerance")["accuracy"]
    assert stasis.loc[1.0] == pytest.approx((5 + 6 + 4 + 6) / 28)  # pooled per-ball Q3
    assert stasis.is_monotonic_increasing


def test_the_tolerance_curve_is_over_answered_balls_so_missing_answers_rank_nothing(
    units: pd.DataFrame,
) -> None:
    model = tolerance_curve(units).query("run == 'litellm_model'")
    q3 = units[(units["run"] == "litellm_model") & (units["task"] == "q3")]
    assert (model["balls"] == (q3["status"] == "ok").sum()).all()  # 21 of 28: 7 never sent
    # the oracle with half its calls failed is still right on every ball it answered ...
    failed = units.copy()
    oracle_q3 = (failed["run"] == "baseline_oracle") & (failed["task"] == "q3")
    failed.loc[oracle_q3 & (failed["horizon"] == failed["horizon"].min()), "status"] = "api_error"
    oracle = tolerance_curve(failed).query("run == 'baseline_oracle'")
    assert (oracle["accuracy"] == 1.0).all() and 0 < oracle["balls"].iloc[0] < oracle_q3.sum()
    # ... and a run with no answer at all has no curve rather than a line at 0%
    failed.loc[oracle_q3, "status"] = "missing"
    oracle = tolerance_curve(failed).query("run == 'baseline_oracle'")
    assert oracle["accuracy"].isna().all() and (oracle["balls"] == 0).all()


def test_diagnostics_are_registered_for_their_tasks(registry: Registry) -> None:
    assert [d.name for d in registry.diagnostics_for(["q1"])] == ["q1_confusion", "stasis"]
    names = [d.name for d in registry.diagnostics_for(["q3"])]
    assert names == ["q3_distance", "q3_distance_by_horizon", "q3_tolerance", "stasis"]
