"""Bad input to a run: one clear error naming the file and field; nothing done is lost."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from bpb_core.errors import BadInput
from bpb_core.registry import Registry
from bpb_core.run_folder import completed
from bpb_core.runner import run_eval
from bpb_core.runner.options import RunOptions


def test_missing_image_names_the_file_and_state_mode_needs_none(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    data = tmp_path / "data"
    shutil.copytree(dataset, data)
    (data / "h1/scene_0001/init.png").unlink()
    with pytest.raises(BadInput, match=r"h1/scene_0001/init.png: missing"):
        run_eval(
            data, "baseline:stasis", tmp_path / "a", RunOptions(concurrency=1), registry=registry
        )
    assert not (tmp_path / "a").exists()  # refused before the run folder is made
    result = run_eval(
        data, "baseline:stasis", tmp_path / "b", RunOptions(input_mode="state"), registry=registry
    )
    assert sum(c["ok"] for c in result.statuses.values()) == 18


def test_corrupt_scene_names_file_and_field_and_keeps_finished_answers(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    data = tmp_path / "data"
    shutil.copytree(dataset, data)
    options = RunOptions(concurrency=1)
    run_eval(data, "baseline:oracle", tmp_path / "run", options, registry=registry)
    answered = completed(tmp_path / "run")
    path = data / "h3/scene_0002/init.json"
    scene = json.loads(path.read_text())
    scene["balls"][1]["pos"] = [5.0, 0.5]
    path.write_text(json.dumps(scene))
    for run in ("run", "fresh"):  # refused before any call: scoring could not read the scene
        with pytest.raises(BadInput, match=r"h3/scene_0002/init.json: balls"):
            run_eval(data, "baseline:oracle", tmp_path / run, options, registry=registry)
    assert completed(tmp_path / "run") == answered  # the earlier answers stay
    assert len(answered) == 18
    assert not (tmp_path / "fresh").exists()


def test_unknown_task_and_bad_concurrency(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    with pytest.raises(BadInput, match=r"unknown task 'q4'; known tasks: (\w+, )*q1, q2, q3"):
        run_eval(dataset, "baseline:stasis", tmp_path, RunOptions(tasks=("q4",)), registry=registry)
    with pytest.raises(BadInput, match="--concurrency"):
        run_eval(dataset, "baseline:stasis", tmp_path, RunOptions(concurrency=0), registry=registry)


def test_the_oracle_refuses_a_dataset_whose_simulator_is_not_installed(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    data = tmp_path / "data"
    shutil.copytree(dataset, data)
    manifest = json.loads((data / "dataset.json").read_text())
    (data / "dataset.json").write_text(json.dumps({**manifest, "config": {"simulator": "gone"}}))
    with pytest.raises(BadInput) as caught:
        run_eval(data, "baseline:oracle", tmp_path / "oracle", registry=registry)
    assert str(caught.value) == (
        f"{data}/dataset.json: config: names simulator 'gone', which is not installed "
        "(installed: analytic, pymunk); baseline:oracle runs it"
    )
    assert not (tmp_path / "oracle").exists()
    result = run_eval(data, "baseline:stasis", tmp_path / "stasis", registry=registry)
    assert sum(c["ok"] for c in result.statuses.values()) == 18


SPEC_PROBLEMS = [
    ("nocolon", "'nocolon': expected NAME:MODEL, e.g. baseline:stasis"),
    ("baseline:nosuch", "baseline:nosuch: the billiards scene family offers no such prediction"),
    ("litellm:openai/gpt-5", "litellm:openai/gpt-5: openai/gpt-5: environment variable "
     "OPENAI_API_KEY is not set"),
]  # fmt: skip


@pytest.mark.parametrize(("spec", "problem"), SPEC_PROBLEMS, ids=["spec", "family", "preflight"])
def test_a_bad_adapter_is_named_by_the_callers_own_parameter_or_flag(
    dataset: Path,
    tmp_path: Path,
    registry: Registry,
    monkeypatch: pytest.MonkeyPatch,
    capfd: pytest.CaptureFixture[str],
    spec: str,
    problem: str,
) -> None:
    # The library said "--adapter ..." to callers who passed adapter= or adapters=.
    import asyncio

    import bpb_core
    from support.inprocess import bpb

    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    out, kw = tmp_path / "out", {"registry": registry}
    calls = {
        "adapter": lambda: bpb_core.run_eval(dataset, spec, out, **kw),
        "adapters": lambda: bpb_core.evaluate(dataset, [spec], out, **kw),
    }
    for name, call in calls.items():
        with pytest.raises(BadInput) as caught:
            call()
        assert str(caught.value).startswith(f"{name} {problem}")
    with pytest.raises(BadInput) as caught:
        asyncio.run(bpb_core.evaluate_async(dataset, spec, out, **kw))
    assert str(caught.value).startswith(f"adapters {problem}")
    done = bpb(capfd, "run", "--data", str(dataset), "--adapter", spec, "--out", str(out))
    assert done.returncode == 2
    [line] = done.stderr.strip().splitlines()
    assert line.startswith(f"error: --adapter {problem}")
    assert not out.exists()
