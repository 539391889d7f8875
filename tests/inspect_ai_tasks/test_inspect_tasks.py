"""bpb's tasks inside Inspect AI: a real ``inspect_ai.eval`` on a bpb dataset through Inspect's
entry point (``bpb/q1`` ...), against Inspect custom-model APIs that answer from the ground
truth or badly; the scores equal bpb's own on the same replies."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from inspect_ai import eval as inspect_eval
from inspect_ai.log import EvalLog

from bpb_core import RunOptions, leaderboard, run_eval
from support.inspect_models import ExampleAdapter
from support.paths import DOCS

pytestmark = pytest.mark.usefixtures("quiet_inspect")


@pytest.fixture
def quiet_inspect(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    import support.inspect_models  # noqa: F401 (registers bpbtest/truth and bpbtest/example)

    monkeypatch.setenv("INSPECT_DISPLAY", "none")
    monkeypatch.setenv("INSPECT_LOG_DIR", str(tmp_path / "logs"))
    monkeypatch.chdir(tmp_path)


def metrics(log: EvalLog) -> dict[str, float]:
    assert log.status == "success", log.error
    assert log.results is not None
    (score,) = log.results.scores
    return {name: m.value for name, m in score.metrics.items()}


def test_truth_scores_full_marks(small_dataset: Path) -> None:
    (log,) = inspect_eval(
        "bpb/total",
        model="bpbtest/truth",
        model_args={"data": str(small_dataset)},
        task_args={"data": str(small_dataset)},
    )
    assert metrics(log) == {"q1": 1.0, "q2": 1.0, "q3": 1.0, "total": 1.0}
    assert log.samples is not None and len(log.samples) == 6 * 3


def test_a_bad_model_scores_as_bpb_scores_it(small_dataset: Path, tmp_path: Path) -> None:
    (log,) = inspect_eval(
        "bpb/total", model="bpbtest/example", task_args={"data": str(small_dataset)}
    )
    found = metrics(log)
    run = run_eval(small_dataset, ExampleAdapter(), tmp_path / "run", RunOptions())
    board = leaderboard(run).iloc[0]
    expected = {name: float(board[name]) for name in ("q1", "q2", "q3", "total")}
    assert found == pytest.approx(expected, abs=1e-12)
    assert 0.0 < found["total"] < 1.0 and found["q1"] != found["q2"]


def test_scores_carry_every_ball_and_wall(small_dataset: Path) -> None:
    logs = inspect_eval(
        ["bpb/q1", "bpb/q2"],
        model="bpbtest/example",
        task_args={"data": str(small_dataset), "horizons": "3", "limit": 1},
    )
    units: dict[str, Any] = {}
    for log in logs:
        assert log.samples is not None and len(log.samples) == 1
        (sample,) = log.samples
        assert sample.scores is not None
        (score,) = sample.scores.values()
        assert score.metadata is not None
        units[score.metadata["task"]] = score.metadata["units"]
        right = sum(unit["correct"] for unit in score.metadata["units"])
        rule_all = score.metadata["task"] == "q2"
        expected = float(right == len(score.metadata["units"])) if rule_all else right / 6
        assert score.value == pytest.approx(expected)
    assert [u["unit"] for u in units["q1"]] == ["1", "2", "3", "4", "5", "6"]
    assert [u["unit"] for u in units["q2"]] == ["TOP", "BOTTOM", "LEFT", "RIGHT"]
    assert {"truth", "pred", "correct"} <= set(units["q2"][0])


def test_the_documented_experiment_is_at_most_ten_lines(tmp_path: Path) -> None:
    page = (DOCS / "inspect.md").read_text(encoding="utf-8")
    example = re.search(r"```python\n(.*?)```", page, re.S)
    assert example is not None
    code = example.group(1)
    assert len([line for line in code.splitlines() if line.strip()]) <= 10
    model = 'model="bpbtest/truth", model_args={"data": "data"}'
    namespace: dict[str, Any] = {}
    exec(code.replace('model="openai/gpt-4o"', model), namespace)
    assert metrics(namespace["logs"][0])["total"] == 1.0
