"""The summary ``bpb run`` prints: answered-only scores and completeness first, the strict
score beside, and what is left to resume."""

from __future__ import annotations

from pathlib import Path

import pytest

from bpb_core.cli.run_cmd import show_summary
from bpb_core.registry import make_registry


def test_failures_are_not_read_as_wrong_answers(
    runs: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    show_summary([runs / "baseline_stasis", runs / "litellm_model"], make_registry())
    out, err = capsys.readouterr()
    stasis = next(line for line in out.splitlines() if "baseline:stasis" in line)
    assert "87.5% (87.5%)" in stasis and "71.2% (71.2%)" in stasis  # answered (strict)
    model = next(line for line in out.splitlines() if "litellm:model" in line)
    # every task of the model has a horizon only half answered: no score, never a 0%
    assert model.count("left out") == 4 and "66.7%" in model and "0.0%" not in model
    expected = (
        "litellm_model: incomplete: 1 call failed on infrastructure and 3 calls never sent, "
        "re-run to resume"
    )
    assert expected in " ".join(err.split())
    assert (runs / "litellm_model" / "scores.csv").is_file()
