"""Q1 metrics beside per-ball accuracy: the do-nothing baseline's high per-ball accuracy is
exposed by recall, F1 and balanced accuracy (numbers worked out in support/reports_fixture)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings, strategies as st

from bpb_core.capabilities import ReportsMetrics
from bpb_core.registry import Registry
from bpb_core.report.build import build_report
from bpb_core.results import load_results
from bpb_core.results.tables import RUN_COLUMNS
from bpb_tasks.questions.labels import q1_metrics


def _answered_q1(runs: Path, registry: Registry) -> pd.DataFrame:
    units = load_results(runs, registry=registry).units
    return units[(units["task"] == "q1") & ~units["status"].isin(["api_error", "missing"])]


def test_stasis_scores_high_per_ball_and_at_chance_on_balanced_accuracy(
    runs: Path, registry: Registry
) -> None:
    table = q1_metrics(_answered_q1(runs, registry)).set_index("run")
    stasis = table.loc["baseline_stasis"]
    assert stasis["per_ball"] == pytest.approx(0.875)  # the paper's metric flatters it
    # exact set: h1_0001 and h2_0001 (no contact) right, h1_0000 and h2_0000 wrong
    assert stasis["exact_set"] == 0.5
    assert (stasis["recall"], stasis["f1"], stasis["balanced_accuracy"]) == (0.0, 0.0, 0.5)
    assert np.isnan(stasis["precision"])  # it never says T
    assert (stasis["tp"], stasis["fn"], stasis["tn"]) == (0, 3, 21)
    oracle = table.loc["baseline_oracle"]
    assert oracle[["per_ball", "exact_set", "recall", "f1", "balanced_accuracy"]].eq(1.0).all()


@settings(max_examples=40, deadline=None)
@given(truth=st.lists(st.booleans(), min_size=2, max_size=60), constant=st.booleans())
def test_any_constant_answer_scores_half_on_balanced_accuracy(
    truth: list[bool], constant: bool
) -> None:
    if all(truth) or not any(truth):
        truth = [True, False, *truth]
    n = len(truth)
    units = pd.DataFrame(
        {
            "run": "r", "adapter": "a", "model": "m", "baseline": False,
            "task": "q1", "horizon": 1.0, "index": np.arange(n) // 6, "status": "ok",
            "truth": ["T" if t else "F" for t in truth], "pred": "T" if constant else "F",
            "duplicate": False, "correct": [t == constant for t in truth],
        }
    )  # fmt: skip
    row = q1_metrics(units).iloc[0]
    assert row["balanced_accuracy"] == pytest.approx(0.5)
    assert row["recall"] == (1.0 if constant else 0.0)


def test_reports_show_the_metrics_and_blank_them_for_incomplete_runs(
    runs: Path, registry: Registry, tmp_path: Path
) -> None:
    assert isinstance(registry.scorer_for("q1"), ReportsMetrics)
    report = build_report(runs, tmp_path / "out", n_boot=20, gallery_size=0, registry=registry)
    table = report.tables["q1_metrics"].set_index("run")
    assert list(table.columns[: len(RUN_COLUMNS) - 1]) == RUN_COLUMNS[1:]
    assert table.loc["baseline_stasis", "balanced_accuracy"] == 0.5
    assert table.loc["litellm_model", ["per_ball", "recall"]].isna().all()  # q1 left out
    assert table.loc["litellm_model", "complete"] == pytest.approx(8 / 12)
    summary = report.summary_json()
    stasis = next(r for r in summary["metrics"]["q1"] if r["run"] == "baseline_stasis")
    assert stasis["balanced_accuracy"] == 0.5 and stasis["precision"] is None
    assert "chance-corrected" in summary["metric_notes"]["q1"]["balanced_accuracy"]
    page = (tmp_path / "out" / "report.html").read_text()
    assert "q1 metrics beside accuracy" in page and "chance-corrected" in page
