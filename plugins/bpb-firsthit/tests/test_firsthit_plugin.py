"""The example task plugin: its rules, and bpb running it end to end with no change in core."""

from __future__ import annotations

import contextlib
import csv
import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from bpb_firsthit.scorer import FirstHitScorer
from bpb_firsthit.task import FirstHitTask, first_hit
from hypothesis import given, settings, strategies as st

from bpb_core import ParseFailure, PromptOptions, make_registry
from bpb_tasks.billiards.scene.model import Ball, Scene
from bpb_tasks.billiards.truth.final import EventRecord, FinalState

BPB = str(Path(sys.executable).with_name("bpb"))
SCENE = Scene(
    scene_id="h1_0000",
    horizon=1.0,
    balls=[Ball(id=0, pos=(0.5, 0.5), vel=(1.0, 0.0))]
    + [Ball(id=i, pos=(0.2 + 0.25 * i, 0.2)) for i in range(1, 7)],
)


def truth(*events: tuple[str, list[int]]) -> FinalState:
    log = [EventRecord(t=0.1 * k, kind=kind, ids=ids) for k, (kind, ids) in enumerate(events)]  # type: ignore[arg-type]
    return FinalState(scene_id="h1_0000", horizon=1.0, q1=[], q2=[], predictions=[], events=log)


def test_expected_is_the_first_cue_ball_contact() -> None:
    assert (
        first_hit(truth(("wall", [0]), ("ball", [2, 5]), ("ball", [0, 4]), ("ball", [0, 1]))) == 4
    )
    assert first_hit(truth(("wall", [0]), ("ball", [1, 2]), ("stop", [0]))) is None
    assert FirstHitTask().expected(truth()) == {"first": None}


def test_parse_reads_the_answer_from_prose_and_rejects_other_balls() -> None:
    task, cot = FirstHitTask(), PromptOptions(cot=True)
    assert task.parse('I think... {"first": 3}', SCENE, cot).value == {"first": 3}
    assert task.parse('{"first": null}', SCENE, PromptOptions()).value == {"first": None}
    for bad in ('{"first": 0}', '{"first": 9}', '{"first": "x"}', '{"second": 1}', "none"):
        with pytest.raises(ParseFailure):
            task.parse(bad, SCENE, PromptOptions())


def test_the_prompt_asks_about_the_scene_and_shows_the_format() -> None:
    (message,) = FirstHitTask().messages(SCENE, None, PromptOptions(input_mode="state"))
    text = message.parts[0].text  # type: ignore[union-attr]
    assert "Task FIRSTHIT" in text and '{"first": 1}' in text and "[1, 2, 3, 4, 5, 6]" in text


@settings(max_examples=150, deadline=None)
@given(st.text(max_size=300))
def test_parse_only_ever_raises_parse_failure(text: str) -> None:
    with contextlib.suppress(ParseFailure):
        FirstHitTask().parse(text, SCENE, PromptOptions(cot=True))


def test_scorer_rules() -> None:
    import pandas as pd

    scorer = FirstHitScorer()
    hit = truth(("ball", [0, 4]))
    cases = [
        ({"first": 4}, "ok", True),
        ({"first": "4"}, "ok", True),
        ({"first": None}, "ok", False),
        ({"first": 4}, "parse_error", False),
        (None, "api_error", False),
    ]
    for answer, status, right in cases:
        (unit,) = scorer.units(answer, hit, SCENE)
        frame = pd.DataFrame([unit._asdict()]).assign(status=status)
        assert bool(scorer.score(frame)["correct"].iloc[0]) is right, (answer, status)
    wrong = pd.DataFrame({"pred": ["none"], "truth": ["4"], "correct": [False]})
    assert scorer.explain(wrong) == ["first hit: said none, truth 4"]


def test_registered_through_its_own_entry_point() -> None:
    registry = make_registry()
    assert registry.get("task", "firsthit").distribution == "bpb-firsthit"
    assert registry.task_info("firsthit").family == "billiards"
    assert [d.name for d in registry.diagnostics_for(["firsthit"])] == ["firsthit_outcomes"]


def bpb(*args: str | Path, env: dict[str, str] | None = None) -> str:
    done = subprocess.run(
        [BPB, *map(str, args)], capture_output=True, text=True, timeout=300,
        env={**os.environ, "COLUMNS": "200", **(env or {})},
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("firsthit") / "data"
    bpb("generate", "--out", root, "--per-horizon", "4", "--horizons", "1,3", "--seed", "5",
        "--no-images", "--workers", "1")  # fmt: skip
    return root


@pytest.fixture
def fake_server(data: Path) -> Iterator[str]:
    """The local OpenAI-compatible server, pointed at the dataset; yields its api_base."""
    args = [sys.executable, "-m", "bpb_testing.fakeserver", "--data", str(data)]
    process = subprocess.Popen(args, stdout=subprocess.PIPE, text=True)
    try:
        assert process.stdout is not None
        port = int(process.stdout.readline().split()[1])
        yield f"http://127.0.0.1:{port}/v1"
    finally:
        process.kill()
        process.wait()


def test_end_to_end_baselines_litellm_and_report(
    data: Path, tmp_path: Path, fake_server: str
) -> None:
    runs = tmp_path / "runs"
    bpb("run", "--data", data, "--out", runs, "--tasks", "q1,q2,q3,firsthit", "--input-mode",
        "state", "--adapter", "baseline:oracle", "--adapter", "baseline:stasis")  # fmt: skip
    bpb("run", "--data", data, "--out", runs, "--tasks", "firsthit", "--input-mode", "state",
        "--adapter", "litellm:openai/fake", "--api-base", fake_server,
        env={"OPENAI_API_KEY": "sk-dummy"})  # fmt: skip
    summary = json.loads(bpb("report", runs, "--json", "--bootstrap", "20"))
    board = {row["run"]: row for row in summary["leaderboard"]}
    assert board["baseline_oracle"]["firsthit"] == 1.0
    assert board["litellm_openai_fake"]["firsthit"] == 1.0
    with (data / "index.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    by_horizon: dict[str, list[bool]] = {}
    for row in rows:
        by_horizon.setdefault(row["horizon"], []).append(row["cue_collision"] == "false")
    no_hit = sum(sum(v) / len(v) for v in by_horizon.values()) / len(by_horizon)
    assert board["baseline_stasis"]["firsthit"] == pytest.approx(no_hit)  # says "none" always
    outcomes = {r["run"]: r for r in summary["diagnostics"]["firsthit_outcomes"]}
    assert outcomes["baseline_stasis"]["hit_said_none"] == 1.0
    assert outcomes["baseline_oracle"]["hit_accuracy"] == 1.0
    assert board["baseline_oracle"]["total"] == 1.0  # the paper's suite still applies
    out = tmp_path / "report"
    bpb("report", runs, "--out", out, "--bootstrap", "20")
    assert (out / "tables" / "firsthit_outcomes.csv").is_file()
    page = (out / "report.html").read_text()
    assert "First hit outcomes" in page  # the plugin's diagnostic
    assert "First object ball hit wrong" in page  # the gallery heads by the task title
