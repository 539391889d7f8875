"""Fixtures of the report tests; the hand-made data lives in ``reports_fixture``."""

from __future__ import annotations

from pathlib import Path

import pytest
from reports_fixture import (
    all_answers,
    model_answers,
    oracle_answer,
    stasis_answer,
    write_dataset,
    write_run,
)


@pytest.fixture
def runs(tmp_path: Path) -> Path:
    """``tmp_path/runs`` holding the oracle, stasis and model run folders."""
    dataset = write_dataset(tmp_path / "data")
    runs = tmp_path / "runs"
    write_run(runs / "baseline_oracle", "baseline:oracle", dataset, all_answers(oracle_answer))
    write_run(runs / "baseline_stasis", "baseline:stasis", dataset, all_answers(stasis_answer))
    write_run(runs / "litellm_model", "litellm:model", dataset, model_answers())
    return runs
