"""A third-party scene family end to end: ``bpb-tiny`` adds the ``slider`` family, its simulator,
task, scorer and diagnostic with no change in bpb's core.

The plugin is installed for real (a ``*.dist-info`` with a ``bpb`` entry point on
``PYTHONPATH``) and every step runs through the real ``bpb`` console script: list, generate,
simulate, run (baselines and litellm against the fake OpenAI server), report.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, NamedTuple

import pytest
from bpb_tiny import hooks  # importable here too: pytest puts tests/third_party on sys.path

from bpb_core.capabilities import (
    Calibrating,
    DrawingStats,
    DrawsOverlay,
    ExplainsErrors,
    Picturing,
    Predicting,
    Tallying,
)
from bpb_core.errors import ParseFailure
from bpb_core.interfaces import PromptOptions, SceneFamily
from bpb_core.registry import make_registry
from bpb_core.results.frames import load_results
from support.fake_openai import fake_server
from support.paths import tree
from support.tiny_plugin import TinyInstall, install_tiny


class Report(NamedTuple):
    """What ``bpb report --json --out`` gave: the JSON summary and the output folder."""

    summary: dict[str, Any]
    out: Path


GENERATE = ("--family", "slider", "--per-horizon", "4", "--horizons", "1,2", "--seed", "3")
TOLERANCE_SHARE = 0.02  # the task's stated tolerance: 2% of the track length


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> TinyInstall:
    """bpb-tiny installed into a fresh site folder."""
    return install_tiny(tmp_path_factory.mktemp("tiny") / "site")


@pytest.fixture(scope="module")
def data(tiny: TinyInstall, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The slider dataset of :data:`GENERATE`, made on 2 workers."""
    out = tmp_path_factory.mktemp("slider") / "D"
    tiny.ok("generate", "--out", out, *GENERATE, "--workers", "2")
    return out


@pytest.fixture(scope="module")
def runs(tiny: TinyInstall, data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The oracle and stasis baseline runs on :func:`data` (default tasks)."""
    out = tmp_path_factory.mktemp("runs")
    for spec in ("baseline:oracle", "baseline:stasis"):
        tiny.ok("run", "--data", data, "--adapter", spec, "--out", out)
    return out


@pytest.fixture(scope="module")
def report(tiny: TinyInstall, runs: Path, tmp_path_factory: pytest.TempPathFactory) -> Report:
    """``bpb report --json --out X`` of :func:`runs`: the printed summary and the folder X."""
    out = tmp_path_factory.mktemp("report") / "X"
    printed = tiny.ok("report", runs, "--json", "--out", out, "--bootstrap", "50")
    return Report(json.loads(printed), out)


def scenes(data: Path) -> list[tuple[dict[str, Any], dict[str, Any]]]:
    """``(init.json, final.json)`` of every scene, in dataset order."""
    folders = sorted(data.glob("h*/scene_*"), key=lambda p: (float(p.parent.name[1:]), p.name))
    return [
        (json.loads((f / "init.json").read_text()), json.loads((f / "final.json").read_text()))
        for f in folders
    ]


def scores(summary: dict[str, Any]) -> dict[str, float]:
    """``slider_stop`` leaderboard score per run."""
    return {row["run"]: row["slider_stop"] for row in summary["leaderboard"]}


def stepped(init: dict[str, Any], dt: float = 1e-4) -> tuple[float, int]:
    """Position and wall hits at the horizon by small time steps (independent of bpb_tiny)."""
    x, v, a, length = init["x0"], init["v0"], init["mu_g"], init["length"]
    hits, t = 0, 0.0
    while t < init["horizon"] and v != 0.0:
        sign = 1.0 if v > 0 else -1.0
        step = min(dt, init["horizon"] - t, abs(v) / a)
        x += v * step - sign * a * step * step / 2
        v = 0.0 if step == abs(v) / a else v - sign * a * step
        while not 0.0 <= x <= length:  # reflect off the wall passed during the step
            x, v, hits = (2 * length - x if x > length else -x), -v, hits + 1
        t += step
    return x, hits


def test_the_family_and_its_components_are_listed(tiny: TinyInstall) -> None:
    assert "slider" in tiny.ok("list", "scene-families")
    assert "slider_stop" in tiny.ok("list", "tasks")
    assert "slider-exact" in tiny.ok("list", "simulators")
    assert "slider_errors" in tiny.ok("list", "diagnostics")


def test_the_family_offers_the_optional_capabilities() -> None:
    registry = make_registry([hooks], entry_points=False)
    family = registry.scene_family("slider")
    assert isinstance(family, SceneFamily)
    for capability in (Tallying, DrawingStats, Predicting, Picturing):
        assert isinstance(family, capability), capability.__name__
    assert not isinstance(family, Calibrating)
    scorer = registry.scorer_for("slider_stop")
    assert isinstance(scorer, ExplainsErrors) and isinstance(scorer, DrawsOverlay)
    assert registry.tasks_for("slider", default_only=True) == ["slider_stop"]


def test_generation_is_byte_identical_across_reruns_and_worker_counts(
    tiny: TinyInstall, data: Path, tmp_path: Path
) -> None:
    tiny.ok("generate", "--out", tmp_path / "again", *GENERATE, "--workers", "2")
    tiny.ok("generate", "--out", tmp_path / "one", *GENERATE, "--workers", "1")
    made = tree(data)
    assert tree(tmp_path / "again") == made
    assert tree(tmp_path / "one") == made
    for folder in data.glob("h*/scene_*"):
        assert {p.name for p in folder.iterdir()} == {"init.json", "final.json", "init.png"}
        assert (folder / "init.png").read_bytes().startswith(b"\x89PNG")
    assert made["stats/bounces.png"].startswith(b"\x89PNG")
    manifest = json.loads(made["dataset.json"])
    assert manifest["config"]["family"] == "slider" and manifest["scenes"] == 8
    assert manifest["plugins"]["scene_family"] == "slider (bpb-tiny 0.1.0)"
    assert {"bounce_rate", "mean_bounces"} <= set(manifest["summary"]["h2"])


def test_ground_truth_agrees_with_a_stepped_simulation(data: Path) -> None:
    for init, final in scenes(data):
        x, hits = stepped(init)
        assert final["stable"] is True  # no wall hit within 1 ms of the horizon here
        assert hits == final["bounces"], init["scene_id"]
        assert x == pytest.approx(final["x"], abs=2e-6), init["scene_id"]


def test_simulate_reproduces_final_json(tiny: TinyInstall, data: Path) -> None:
    expected = [final for _, final in scenes(data)]
    lines = tiny.ok("simulate", data, "--simulator", "slider-exact", "--stability").splitlines()
    assert [json.loads(line) for line in lines] == expected
    plain = tiny.ok("simulate", data, "--simulator", "slider-exact").splitlines()
    assert [json.loads(line) for line in plain] == [{**f, "stable": None} for f in expected]


def test_oracle_scores_everything(report: Report) -> None:
    assert scores(report.summary)["baseline_oracle"] == 1.0


def test_stasis_scores_what_the_files_say(data: Path, report: Report) -> None:
    by_horizon: dict[float, list[float]] = {}
    for init, final in scenes(data):
        x_right = abs(init["x0"] - final["x"]) <= TOLERANCE_SHARE * init["length"]
        count_right = final["bounces"] == 0
        by_horizon.setdefault(init["horizon"], []).append((x_right + count_right) / 2)
    expected = sum(sum(s) / len(s) for s in by_horizon.values()) / len(by_horizon)
    assert 0.0 < expected < 1.0
    assert scores(report.summary)["baseline_stasis"] == pytest.approx(expected)


def test_litellm_against_the_fake_server_scores_everything_and_sends_the_image(
    tiny: TinyInstall, data: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PYTHONPATH", tiny.env["PYTHONPATH"])  # the server must see the plugin
    with fake_server(data) as server:
        tiny.ok(
            "run", "--data", data, "--adapter", "litellm:openai/fake",
            "--api-base", server.api_base, "--out", tmp_path / "runs",
        )  # fmt: skip
        stats = server.stats()
    assert stats["images"] == 8
    keys = sorted(f"{init['scene_id']}/slider_stop" for init, _ in scenes(data))
    assert sorted(stats["counts"]) == keys  # every prompt recognised, none unknown
    units = load_results(tmp_path / "runs", registry=make_registry([hooks])).units
    assert len(units) == 16 and units["correct"].all()  # 8 scenes x (x, bounces)


def test_a_billiards_task_on_slider_scenes_is_bad_input(
    tiny: TinyInstall, data: Path, tmp_path: Path
) -> None:
    done = tiny.bpb(
        "run", "--data", data, "--tasks", "q1", "--adapter", "baseline:oracle", "--out", tmp_path
    )
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "billiards" in lines[0] and "slider" in lines[0], done.stderr


def test_report_shows_the_task_and_the_diagnostic(report: Report) -> None:
    assert {row["slider_stop"] for row in report.summary["leaderboard"]} == {1.0, 0.25}
    table = report.summary["diagnostics"]["slider_errors"]
    assert list(table[0])[:4] == ["run", "adapter", "model", "baseline"]
    rows = {row["run"]: row for row in table}
    assert rows["baseline_oracle"]["x_within"] == 1.0 and rows["baseline_oracle"]["x_mae"] == 0.0
    assert rows["baseline_stasis"]["bounce_bias"] < 0  # it never counts a hit
    html = (report.out / "report.html").read_text()
    assert "Slider: position and wall-hit errors" in html
    assert "bounces: said 0, truth" in html  # the scorer's explanation
    gallery = list((report.out / "gallery").glob("*.png"))
    assert gallery and all(p.read_bytes().startswith(b"\x89PNG") for p in gallery)
    assert (report.out / "charts" / "slider__position_and_wall_hit_errors.png").is_file()


def test_simulate_without_a_simulator_uses_the_dataset_family(
    tiny: TinyInstall, data: Path
) -> None:
    lines = tiny.ok("simulate", data).splitlines()
    expected = [final for _, final in scenes(data)]
    assert [json.loads(line) for line in lines] == [{**f, "stable": None} for f in expected]


def test_run_without_an_adapter_asks_only_the_baselines_the_family_offers(
    tiny: TinyInstall, data: Path, tmp_path: Path
) -> None:
    tiny.ok("run", "--data", data, "--out", tmp_path)
    ran = sorted(p.name for p in tmp_path.iterdir() if (p / "run.json").is_file())
    assert ran == ["baseline_oracle", "baseline_stasis"]  # the family offers no other prediction
    done = tiny.bpb("run", "--data", data, "--adapter", "baseline:straight", "--out", tmp_path)
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "error: --adapter baseline:straight: the slider scene family offers no such prediction;"
        " known: baseline:oracle, baseline:stasis"
    )


@pytest.mark.parametrize(
    "text",
    ["", "no json here", '{"x": 2.5, "bounces": 1}', '{"x": 0.4, "bounces": -1}',
     '{"x": 0.4, "bounces": true}', '{"x": NaN, "bounces": 1}', "[1, 2]", "{" * 500],
)  # fmt: skip
def test_the_task_parser_raises_only_parse_failure(text: str) -> None:
    from bpb_tiny.scene import SliderScene
    from bpb_tiny.task import SliderStopTask

    scene = SliderScene(scene_id="h1_0000", horizon=1, length=1, mu_g=0.5, x0=0.5, v0=1)
    task = SliderStopTask()
    assert task.parse('ok: {"x": 0.25, "bounces": 2.0}', scene, PromptOptions()).value == {
        "x": 0.25,
        "bounces": 2,
    }
    with pytest.raises(ParseFailure):
        task.parse(text, scene, PromptOptions())
