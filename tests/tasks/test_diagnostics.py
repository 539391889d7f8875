"""Diagnostics and statistics on the hand-made runs (numbers worked out in reports_fixture)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bpb_core.results import load_results
from bpb_core.results.diagnostics import (
    confusion,
    distance_errors,
    stasis_index,
    tolerance_curve,
    usage,
)
from bpb_core.results.tables import leaderboard
from bpb_core.results.uncertainty import bootstrap_ci, paired_comparison, sign_test


@pytest.fixture
def units(runs: Path) -> pd.DataFrame:
    return load_results(runs).units


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
    table = confusion(units).set_index(["run", "task", "unit"])
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


def test_usage_counts_tokens_retries_failures_and_unknown_cost(runs: Path) -> None:
    table = usage(load_results(runs).calls).set_index("run").loc["litellm_model"]
    assert table["calls"] == 9 and table["missing"] == 3
    assert (table["parse_error"], table["api_error"], table["retries"]) == (1, 1, 5)
    assert table["reasoning_tokens"] == 50 and table["cost_unknown"] == 1
    assert table["input_tokens"] == 900


def test_bootstrap_ci_brackets_the_leaderboard_and_is_seeded(units: pd.DataFrame) -> None:
    ci = bootstrap_ci(units, n_boot=500, seed=3)
    board = leaderboard(units).set_index("run")
    for row in ci.itertuples():
        assert row.estimate == pytest.approx(board.loc[row.run, row.metric])
        assert row.lo <= row.estimate <= row.hi
    assert ci.equals(bootstrap_ci(units, n_boot=500, seed=3))
    oracle = ci[ci["run"] == "baseline_oracle"]
    assert (oracle["lo"] == 1.0).all() and (oracle["hi"] == 1.0).all()


def test_paired_comparison_of_oracle_and_stasis(units: pd.DataFrame) -> None:
    table = paired_comparison(units, "baseline_oracle", "baseline_stasis").set_index("metric")
    assert table.loc["total", "diff"] == pytest.approx(1 - 0.7125)
    assert table.loc["q3", ["wins", "losses", "ties"]].tolist() == [4, 0, 0]
    assert table.loc["q3", "p_value"] == pytest.approx(0.125)


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 40), st.integers(0, 40))
def test_sign_test_is_a_symmetric_probability(wins: int, losses: int) -> None:
    p = sign_test(wins, losses)
    assert 0.0 <= p <= 1.0 and p == pytest.approx(sign_test(losses, wins))
    if wins == losses:
        assert p == 1.0


def test_runs_on_different_datasets_are_not_paired(runs: Path, tmp_path: Path) -> None:
    from reports_fixture import all_answers, oracle_answer, write_dataset, write_run

    from bpb_core.errors import BadInput
    from bpb_core.results.uncertainty import all_pairs

    other = write_dataset(tmp_path / "other_data")
    write_run(runs / "litellm_other", "litellm:other", other, all_answers(oracle_answer))
    units = load_results(runs).units
    with pytest.raises(BadInput, match="different datasets"):
        paired_comparison(units, "litellm_other", "litellm_model")
    pairs = all_pairs(units, n_boot=50)
    assert set(zip(pairs["a"], pairs["b"], strict=True)) == {
        ("litellm_model", "baseline_oracle"),
        ("litellm_model", "baseline_stasis"),
    }
