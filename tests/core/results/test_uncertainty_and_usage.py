"""Uncertainty and usage on the hand-made runs (numbers worked out in support/reports_fixture):
bootstrap intervals, paired comparisons, the sign test, tokens and failures per run."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
from hypothesis import given, settings, strategies as st

from bpb_core.registry import Registry
from bpb_core.results import Results, load_results
from bpb_core.results.tables import leaderboard, usage
from bpb_core.results.uncertainty import bootstrap_ci, paired_comparison, sign_test


@pytest.fixture
def results(runs: Path, registry: Registry) -> Results:
    return load_results(runs, registry=registry)


@pytest.fixture
def units(results: Results) -> pd.DataFrame:
    return results.units


def test_usage_counts_tokens_retries_failures_and_unknown_cost(results: Results) -> None:
    table = usage(results.calls).set_index("run").loc["litellm_model"]
    assert table["calls"] == 9 and table["missing"] == 3
    assert (table["parse_error"], table["api_error"], table["retries"]) == (1, 1, 5)
    assert table["reasoning_tokens"] == 50 and table["cost_unknown"] == 1
    assert table["input_tokens"] == 900


def test_bootstrap_ci_brackets_the_leaderboard_and_is_seeded(results: Results) -> None:
    units, suites = results.units, results.suites
    ci = bootstrap_ci(units, suites, n_boot=500, seed=3)
    assert set(ci["metric"]) == {"q1", "q2", "q3", "total"}
    board = leaderboard(units, suites, include_incomplete=True).set_index("run")
    for row in ci.itertuples():
        assert row.estimate == pytest.approx(board.loc[row.run, row.metric])
        assert row.lo <= row.estimate <= row.hi
    assert ci.equals(bootstrap_ci(units, suites, n_boot=500, seed=3))
    oracle = ci[ci["run"] == "baseline_oracle"]
    assert (oracle["lo"] == 1.0).all() and (oracle["hi"] == 1.0).all()


def test_paired_comparison_of_oracle_and_stasis(results: Results) -> None:
    pair = paired_comparison(results.units, "baseline_oracle", "baseline_stasis", results.suites)
    table = pair.set_index("metric")
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


def test_runs_on_different_datasets_are_not_paired(
    runs: Path, tmp_path: Path, registry: Registry
) -> None:
    from bpb_core.errors import BadInput
    from bpb_core.results.uncertainty import all_pairs
    from support.reports_fixture import all_answers, oracle_answer, write_dataset, write_run

    other = write_dataset(tmp_path / "other_data")
    write_run(runs / "litellm_other", "litellm:other", other, all_answers(oracle_answer))
    units = load_results(runs, registry=registry).units
    with pytest.raises(BadInput, match="different datasets"):
        paired_comparison(units, "litellm_other", "litellm_model")
    pairs = all_pairs(units, n_boot=50)
    assert set(zip(pairs["a"], pairs["b"], strict=True)) == {
        ("litellm_model", "baseline_oracle"),
        ("litellm_model", "baseline_stasis"),
    }
