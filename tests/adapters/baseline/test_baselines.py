"""Baselines answer through the same parse path; oracle scores 100%, stasis says nothing moves."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bpb_core.registry import Registry, make_registry
from bpb_core.results import load_results, summary
from bpb_core.run_folder import iter_answers
from bpb_core.runner import evaluate, run_eval, slug
from bpb_core.runner.options import RunOptions
from bpb_tasks.billiards.scene.model import Scene

BASELINES = ["baseline:oracle", "baseline:stasis", "baseline:straight", "baseline:random"]


@pytest.fixture(scope="module")
def runs(dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("baselines")
    options = RunOptions(input_mode="image")
    evaluate(dataset, BASELINES, out, options, registry=make_registry())  # one per module
    return out


def test_oracle_scores_100_percent_on_every_task(runs: Path) -> None:
    results = load_results([runs / "baseline_oracle"])
    table = summary(results.units, results.suites).iloc[0]
    assert (table["q1"], table["q2"], table["q3"], table["total"]) == (1.0, 1.0, 1.0, 1.0)


def test_stasis_answers_no_contact_and_unmoved_everywhere(runs: Path, dataset: Path) -> None:
    records = list(iter_answers(runs / "baseline_stasis"))
    assert len(records) == 18 and all(r.status == "ok" and r.rule for _, r in records)
    for key, record in records:
        assert record.answer is not None
        if record.task in ("q1", "q2"):
            assert {a["answer"] for a in record.answer["answers"]} == {"F"}
        else:
            scene = Scene.model_validate_json((key.dir(dataset) / "init.json").read_text())
            start = {b.id: list(b.pos) for b in scene.balls}
            assert {p["id"]: p["pos"] for p in record.answer["predictions"]} == start


def test_straight_moves_only_the_cue_ball_and_never_hits(runs: Path, dataset: Path) -> None:
    for key, record in iter_answers(runs / "baseline_straight"):
        assert record.answer is not None
        if record.task == "q1":
            assert {a["answer"] for a in record.answer["answers"]} == {"F"}
        if record.task == "q3":
            scene = Scene.model_validate_json((key.dir(dataset) / "init.json").read_text())
            moved = [
                p["id"]
                for p in record.answer["predictions"]
                if p["pos"] != list(scene.ball(p["id"]).pos)
            ]
            assert moved in ([0], [])


def _answers(run_dir: Path) -> dict[tuple[str, str], object]:
    return {(r.scene_id, r.task): r.answer for _, r in iter_answers(run_dir)}


def test_random_is_seeded_from_seed_scene_and_task(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    for name, seed in (("a", 1), ("b", 1), ("c", 2)):
        run_eval(
            dataset, "baseline:random", tmp_path / name, RunOptions(seed=seed), registry=registry
        )
    assert _answers(tmp_path / "a") == _answers(tmp_path / "b")
    assert _answers(tmp_path / "a") != _answers(tmp_path / "c")


def test_run_folder_follows_the_team_contract(runs: Path) -> None:
    run_dir = runs / slug("baseline:oracle")
    manifest = json.loads((run_dir / "run.json").read_text())
    assert manifest["adapter"] == "baseline:oracle" and manifest["dataset_hash"] == "test-2-3"
    assert manifest["started"] and manifest["finished"] and manifest["versions"]["bpb"]
    assert any(p["name"] == "q1" for p in manifest["plugins"])
    record = json.loads((run_dir / "h3/scene_0002/q2.json").read_text())
    assert set(record) == {
        "scene_id",
        "horizon",
        "index",
        "task",
        "adapter",
        "status",
        "answer",
        "rule",
        "finish_reason",
        "attempts",
        "usage",
        "cost",
        "latency",
        "error",
        "input_mode",
        "cot",
    }
    assert record["scene_id"] == "h3_0002" and record["cot"] is True
