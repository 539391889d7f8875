"""Run options researchers expect: --scenes, --sample, --epochs, --temperature; bpb prompt."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from bpb_core.errors import BadInput
from bpb_core.interfaces import PromptOptions
from bpb_core.model_calls import ImagePart, ModelRequest, ModelResponse
from bpb_core.registry import Registry
from bpb_core.results import load_results
from bpb_core.results.tables import accuracy
from bpb_core.run_folder import iter_answers, read_attempts
from bpb_core.runner import RunOptions, run_eval
from support.inprocess import bpb


@dataclasses.dataclass
class Recording:
    """The oracle, remembering the temperature of every request."""

    oracle: object
    name: str = "fake:recording"
    temperatures: list[float] = dataclasses.field(default_factory=list)

    async def complete(self, request: ModelRequest) -> ModelResponse:
        self.temperatures.append(request.temperature)
        answer: ModelResponse = await self.oracle.complete(request)  # type: ignore[attr-defined]
        return answer


def _answered(run_dir: Path) -> set[tuple[str, str, int]]:
    return {(r.scene_id, r.task, r.epoch) for _, r in iter_answers(run_dir)}


def test_scenes_asks_only_those_and_names_an_unknown_id(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    options = RunOptions(tasks=("q1",), scenes=("h3_0002", "h1_0001"))
    run_eval(dataset, "baseline:oracle", tmp_path / "run", options, registry=registry)
    assert _answered(tmp_path / "run") == {("h1_0001", "q1", 1), ("h3_0002", "q1", 1)}
    table = accuracy(load_results(tmp_path / "run", registry=registry).units)
    assert list(table["expected"]) == [1, 1] and list(table["completeness"]) == [1.0, 1.0]
    with pytest.raises(BadInput, match="--scenes: 'h9_0000' is not a scene of the selection"):
        run_eval(dataset, "baseline:oracle", tmp_path / "x", RunOptions(scenes=("h9_0000",)),
                 registry=registry)  # fmt: skip
    assert not (tmp_path / "x").exists()


def test_sample_is_seeded_and_the_results_expect_only_the_sample(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    def sampled(folder: str, seed: int) -> set[str]:
        options = RunOptions(tasks=("q2",), sample=3, seed=seed)
        run_eval(dataset, "baseline:oracle", tmp_path / folder, options, registry=registry)
        return {scene for scene, _, _ in _answered(tmp_path / folder)}

    first = sampled("a", 1)
    assert len(first) == 3 and sampled("b", 1) == first
    assert any(sampled(f"c{seed}", seed) != first for seed in (2, 3, 4))
    units = load_results(tmp_path / "a", registry=registry).units
    assert set(units["scene_id"].astype(str)) == first and "missing" not in set(units["status"])
    with pytest.raises(BadInput, match="--sample: 7 is more than the 6 scenes selected"):
        run_eval(dataset, "baseline:oracle", tmp_path / "x", RunOptions(sample=7),
                 registry=registry)  # fmt: skip


def test_epochs_ask_each_pair_k_times_and_the_frame_keeps_an_epoch_column(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    run_dir = tmp_path / "run"
    adapter = Recording(registry.adapter("baseline:oracle"))
    options = RunOptions(tasks=("q1", "q3"), epochs=2, temperature=0.7)
    result = run_eval(dataset, adapter, run_dir, options, registry=registry, spec="fake:rec")
    assert sum(c["ok"] for c in result.statuses.values()) == 24 and len(adapter.temperatures) == 24
    assert set(adapter.temperatures) == {0.7}
    assert (run_dir / "h1/scene_0000/q1.json").is_file()
    assert (run_dir / "h1/scene_0000/q1.e2.json").is_file()
    assert {e["epoch"] for e in read_attempts(run_dir)} == {1, 2}
    units = load_results(run_dir, registry=registry).units
    assert sorted(units["epoch"].unique()) == [1, 2] and str(units["epoch"].dtype) == "int32"
    table = accuracy(units)
    assert set(table["expected"]) == {6} and set(table["accuracy"]) == {1.0}
    more = dataclasses.replace(options, epochs=3)  # a third sample of every pair: 12 calls more
    run_eval(dataset, adapter, run_dir, more, registry=registry, spec="fake:rec")
    assert len(adapter.temperatures) == 36
    with pytest.raises(BadInput, match=r"temperature: this folder holds a run with 0\.7, not 0\.0"):
        run_eval(dataset, adapter, run_dir, RunOptions(tasks=("q1", "q3")), registry=registry,
                 spec="fake:rec")  # fmt: skip


def test_prompt_prints_the_messages_a_run_sends(
    dataset: Path, tmp_path: Path, registry: Registry, capfd: pytest.CaptureFixture[str]
) -> None:
    run_eval(dataset, "baseline:oracle", tmp_path / "run", RunOptions(tasks=("q1",)),
             registry=registry)  # fmt: skip
    sent = {e["scene_id"]: e["image_sha256"] for e in read_attempts(tmp_path / "run")}
    folder = dataset / "h3" / "scene_0001"
    by_path = bpb(capfd, "prompt", str(folder), "--task", "q1")
    by_id = bpb(capfd, "prompt", "h3_0001", "--data", str(dataset), "--task", "q1")
    assert by_path.returncode == 0, by_path.stderr
    assert by_path.stdout == by_id.stdout
    task = registry.task("q1")
    scene = registry.scene_family("billiards").scene_model.model_validate_json(
        (folder / "init.json").read_text()
    )
    image = (folder / "init.png").read_bytes()
    messages = task.messages(scene, image, PromptOptions("image", task.default_cot))
    for message in messages:
        assert f"--- {message.role} ---" in by_path.stdout
        for part in message.parts:
            if isinstance(part, ImagePart):
                assert f"{len(image):,} bytes, sha256 {sent['h3_0001']}]" in by_path.stdout
            else:
                assert part.text in by_path.stdout
    assert "base64" not in by_path.stdout and len(by_path.stdout) < 20_000
    bad = bpb(capfd, "prompt", "h9_0000", "--data", str(dataset))
    assert bad.returncode == 2 and "no scene with id 'h9_0000'" in bad.stderr
