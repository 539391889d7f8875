"""The paper beside you: ``bpb report`` shows the scores the paper states next to a run of the
same model (matched by its alias), with the run's interval and the difference, and says when a
run cannot be compared (it lacks horizons the figure covers)."""

from __future__ import annotations

import functools
import json
import re
from collections.abc import Callable
from pathlib import Path

import pytest

from bpb_core.dataset import generate_dataset
from bpb_core.registry import model_key
from bpb_tasks.paper.figures import STATED
from support.fake_openai import fake_server
from support.inprocess import Done, bpb

RunBpb = Callable[..., Done]


@pytest.fixture(scope="module")
def five_horizons(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("paper") / "data"
    return generate_dataset(out, 2, [1.0, 2.0, 3.0, 4.0, 5.0], seed=3, images=False, workers=1)


@pytest.fixture
def cli(capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> RunBpb:
    monkeypatch.setenv("OPENAI_API_KEY", "sk-test-not-a-real-key")
    monkeypatch.setenv("COLUMNS", "200")
    return functools.partial(bpb, capfd)


def _run(cli: RunBpb, data: Path, out: Path, api_base: str, *extra: str) -> None:
    done = cli("run", "--data", str(data), "--out", str(out), "--adapter", "litellm:gpt-5.5",
               "--api-base", api_base, "--input-mode", "state", *extra)  # fmt: skip
    assert done.returncode == 0, done.stderr


def test_a_gpt_5_5_run_shows_the_paper_s_73_58_total_beside_its_own(
    cli: RunBpb, five_horizons: Path, tmp_path: Path
) -> None:
    runs = tmp_path / "runs"
    with fake_server(five_horizons) as server:
        _run(cli, five_horizons, runs, server.api_base)
    summary = json.loads(cli("report", str(runs), "--json", "--bootstrap", "50").stdout)
    rows = {(r["metric"], r["horizon"]): r for r in summary["references"]}
    stated = {(m, h) for model, m, _, h, _ in STATED if model_key(model) == "gpt-5-5"}
    assert set(rows) == stated  # every figure the paper states for GPT-5.5, and no other
    total = rows[("total", None)]
    assert total["stated"] == pytest.approx(0.7358) and total["where"] == "Results: Overall"
    (board,) = summary["leaderboard"]  # the strict leaderboard: the one run
    assert total["run"] == board["run"]
    own = board["total"]
    assert total["estimate"] == pytest.approx(own)
    assert total["diff"] == pytest.approx(own - 0.7358)
    assert total["lo"] <= total["estimate"] <= total["hi"]
    terminal = cli("report", str(runs), "--bootstrap", "50")
    assert terminal.returncode == 0, terminal.stderr
    line = next(t for t in terminal.stdout.splitlines() if "total mean" in t)
    assert "73.58%" in line and f"{100 * own:.1f}%" in line
    assert "BilliardPhys-Bench" in terminal.stdout  # the source is named
    html = tmp_path / "report"
    assert cli("report", str(runs), "--out", str(html), "--bootstrap", "50").returncode == 0
    page = (html / "report.html").read_text(encoding="utf-8")
    assert "Published figures beside your runs" in page and "73.58%" in page


def test_a_run_on_horizon_1_only_is_compared_on_1_s_figures_and_not_on_means(
    cli: RunBpb, five_horizons: Path, tmp_path: Path
) -> None:
    runs = tmp_path / "runs"
    with fake_server(five_horizons) as server:
        _run(cli, five_horizons, runs, server.api_base, "--horizons", "1")
    summary = json.loads(cli("report", str(runs), "--json", "--bootstrap", "50").stdout)
    rows = {(r["metric"], r["horizon"]): r for r in summary["references"]}
    q3_at_1 = rows[("q3", 1.0)]
    assert q3_at_1["stated"] == pytest.approx(0.8693) and q3_at_1["estimate"] is not None
    assert q3_at_1["note"] == ""
    for mean in (rows[("total", None)], rows[("q1", None)], rows[("q2", None)]):
        assert mean["estimate"] is None and mean["diff"] is None  # no finding from missing data
        assert re.fullmatch(r"not comparable: the run has no scenes at horizon 2, 3, 4, 5 s",
                            mean["note"])  # fmt: skip


def test_baselines_and_other_models_get_no_published_row(
    cli: RunBpb, five_horizons: Path, tmp_path: Path
) -> None:
    runs = tmp_path / "runs"
    done = cli("run", "--data", str(five_horizons), "--out", str(runs), "--input-mode", "state",
               "--adapter", "baseline:oracle")  # fmt: skip
    assert done.returncode == 0, done.stderr
    summary = json.loads(cli("report", str(runs), "--json", "--bootstrap", "20").stdout)
    assert summary["references"] == []
    terminal = cli("report", str(runs), "--bootstrap", "20").stdout
    assert "Published figures" not in terminal


def test_model_names_match_across_aliases_providers_and_spellings() -> None:
    assert model_key("litellm:gpt-5.5") == model_key("GPT-5.5") == model_key("openai/gpt-5.5")
    assert model_key("anthropic/claude-opus-4-7") == model_key("Claude-Opus-4.7")
    assert model_key("litellm:gpt-5.4") != model_key("GPT-5.4-Pro")
