"""A scene family's predict() or picture() that raises, or returns the wrong type, is one
PluginBug naming the family's plugin (exit 3 in the CLI), wherever bpb calls it; so are its
ground_truth() as baseline:oracle and baseline:vision use it and the perceive() and
perception_error() of baseline:vision.

Before, bpb bench score called predict() unchecked (a raise came out as a bare RuntimeError), and
a prediction of the wrong type, in bench score and in the baseline adapter, was blamed on the
task whose expected() choked on it; the failure gallery of bpb report and bpb view called
picture() unchecked (a RuntimeError, or "AttributeError: 'bytes' object has no attribute
'png'"). The oracle's ground_truth() of the wrong type was blamed on the task's expected(), and
baseline:vision blamed each of those flaws on itself (adapter 'baseline:vision': complete()
raised ...). bpb simulate paired the lines of a batch one line short with the wrong scene
files (exit 0), and turned a ground_truth() of the wrong type into bad input or an
AttributeError. The oracle and vision asked without a simulator called the family's
load_config() and simulator_name() unchecked."""

from __future__ import annotations

import asyncio
import functools
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import support.flawed_family
from bpb_adapters.baseline.adapter import BaselineAdapter
from bpb_core import ModelRequest, ModelResponse, Usage, build_messages, load_dataset
from bpb_core.dataset import generate_dataset
from bpb_core.errors import PluginBug
from bpb_core.registry import PluginSource, Registry, make_registry
from bpb_core.report.build import build_report
from bpb_core.results import load_results
from bpb_core.runner import RunOptions, run_eval
from bpb_core.simulate import CHUNK, simulate_lines, simulate_paths
from bpb_core.web.viewer import Viewer
from support.inprocess import Done, bpb

ORIGIN = "plugin 'flawed' (flawed_family) from bpb-flawed 1.2"
FAMILY = "scene family 'flawed'"
PREDICT_FLAWS = [
    ("predictors_type", "predictors is 'stasis'; expected a tuple of names (str)"),
    ("predictors_raise", "predictors raised RuntimeError: predictors exploded"),
    ("predict_raise", "predict('stasis') raised RuntimeError: predict exploded"),
    ("predict_type", "predict('stasis') returned dict; expected FinalState (the family's "
     "truth_model)"),
]  # fmt: skip
PICTURE_FLAWS = [
    ("picture_raise", "picture() raised RuntimeError: picture exploded"),
    ("picture_type", "picture() returned bytes; expected bpb_core.ScenePicture"),
]


@pytest.fixture
def run_bpb(site: Path, capfd: pytest.CaptureFixture[str]) -> Callable[..., Done]:
    """``bpb ARGS`` in this process, ``site`` first on ``sys.path`` (conftest's ``run_bpb``
    runs the console script)."""
    return functools.partial(bpb, capfd, site=site)


def _registry() -> Registry:
    source = PluginSource("flawed", "bpb-flawed", "1.2", "flawed_family")
    return make_registry([(support.flawed_family, source)])


@pytest.fixture(scope="module")
def flawed_data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two scenes of the ``flawed`` family, with images."""
    out = tmp_path_factory.mktemp("flawed") / "data"
    return generate_dataset(out, 2, (1.0,), 0, family="flawed", workers=1, registry=_registry())


class WrongBalls:
    """Always a wrong count, so every scene is in the failure gallery."""

    name = "wrong:balls"

    async def complete(self, request: Any) -> ModelResponse:
        return ModelResponse('{"balls": 99}', Usage(), None, 0.0, "wrong")


@pytest.fixture(scope="module")
def wrong_run(flawed_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    run = tmp_path_factory.mktemp("flawed") / "wrong"
    options = RunOptions(tasks=("balls",), limit=1)
    run_eval(flawed_data, WrongBalls(), run, options, registry=_registry())
    return run


@pytest.mark.parametrize(("flaw", "said"), PREDICT_FLAWS)
def test_the_baseline_names_a_flawed_predict(
    monkeypatch: pytest.MonkeyPatch, flawed_data: Path, tmp_path: Path, flaw: str, said: str
) -> None:
    registry = _registry()
    adapter = BaselineAdapter("baseline:stasis", "stasis", _registry=registry)
    options = RunOptions(tasks=("balls",), limit=1, concurrency=1)
    good = run_eval(flawed_data, adapter, tmp_path / "good", options, registry=registry)
    assert good.statuses["balls"]["ok"] == 1
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    with pytest.raises(PluginBug) as info:
        run_eval(flawed_data, adapter, tmp_path / "run", options, registry=registry)
    assert str(info.value) == f"{ORIGIN}: {FAMILY}: {said}"


TRUTH_TYPE = "ground_truth() returned dict; expected FinalState (the family's truth_model)"
PERCEIVE_TYPE = "perceive() returned dict; expected Scene (the family's scene_model)"


@pytest.mark.parametrize(
    ("model", "flaw", "said"),
    [
        ("oracle", "truth_type", TRUTH_TYPE),
        ("vision", "truth_type", TRUTH_TYPE),
        ("vision", "perceive_raise", "perceive() raised RuntimeError: perceive exploded"),
        ("vision", "perceive_type", PERCEIVE_TYPE),
        ("vision", "perception_error_type", "perception_error() returned list; expected a dict "
         "of named values"),
    ],
)  # fmt: skip
def test_the_oracle_and_vision_name_a_flawed_family(
    monkeypatch: pytest.MonkeyPatch, flawed_data: Path, tmp_path: Path, model: str, flaw: str,
    said: str,
) -> None:  # fmt: skip
    registry = _registry()
    adapter = registry.adapter(f"baseline:{model}")
    options = RunOptions(tasks=("balls",), limit=1, concurrency=1)
    good = run_eval(flawed_data, adapter, tmp_path / "good", options, registry=registry)
    assert good.statuses["balls"]["ok"] == 1
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    with pytest.raises(PluginBug) as info:
        run_eval(flawed_data, registry.adapter(f"baseline:{model}"), tmp_path / "run", options,
                 registry=registry)  # fmt: skip
    assert str(info.value) == f"{ORIGIN}: {FAMILY}: {said}"


SIMULATE_FLAWS = [
    ("ground_truths_short", False, "ground_truths() returned a list of 1 for 2 scenes; "
     "expected a list with one ground truth per scene"),
    ("ground_truths_type", False, "ground_truths() returned dict; expected FinalState (the "
     "family's truth_model)"),
    ("truth_type", True, TRUTH_TYPE),
]  # fmt: skip


@pytest.mark.parametrize(("flaw", "stability", "said"), SIMULATE_FLAWS)
def test_bpb_simulate_names_a_flawed_family(
    monkeypatch: pytest.MonkeyPatch, flawed_data: Path, flaw: str, stability: bool, said: str
) -> None:
    # batches (ground_truths, for many scenes: here from 1) and one by one (ground_truth,
    # taken for --stability)
    import bpb_core.simulate

    monkeypatch.setattr(bpb_core.simulate, "BATCH_MIN", 1)

    def lines() -> list[str]:
        return list(simulate_lines([flawed_data], simulator="flawed-analytic", workers=1,
                                   stability=stability, registry=_registry()))  # fmt: skip

    ids = [json.loads(line)["scene_id"] for line in lines()]
    assert len(set(ids)) == 2  # one line per scene, in order
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    with pytest.raises(PluginBug) as info:
        lines()
    assert str(info.value) == f"{ORIGIN}: {FAMILY}: {said}"


@pytest.mark.parametrize("simulator", ["flawed-analytic", None])
def test_simulate_paths_names_a_flawed_ground_truth(
    monkeypatch: pytest.MonkeyPatch, flawed_data: Path, simulator: str | None
) -> None:
    # None: the dataset's config names 'analytic', registered for billiards; bpb simulate took
    # that family, not the dataset's (which generate pairs with it), and the flaw went unseen
    manifest = json.loads((flawed_data / "dataset.json").read_text())
    assert manifest["config"]["simulator"] == "analytic"
    monkeypatch.setenv("BPB_TEST_FLAW", "truth_type")
    with pytest.raises(PluginBug) as info:
        list(simulate_paths([flawed_data], simulator=simulator, registry=_registry()))
    assert str(info.value) == f"{ORIGIN}: {FAMILY}: {TRUTH_TYPE}"


def test_results_name_unstable_reasons_that_are_not_a_list(
    monkeypatch: pytest.MonkeyPatch, wrong_run: Path
) -> None:
    # a str was joined letter by letter ("q,1"), miscounting the report's stable exclusions
    assert len(load_results([wrong_run], registry=_registry()).units) == 1
    monkeypatch.setenv("BPB_TEST_FLAW", "unstable_reasons_type")
    with pytest.raises(PluginBug) as info:
        load_results([wrong_run], registry=_registry())
    assert str(info.value) == (
        f"{ORIGIN}: {FAMILY}: the ground truth's unstable_reasons is str; expected a list of str"
    )


@pytest.mark.parametrize(("flaw", "said"), PICTURE_FLAWS)
def test_the_gallery_names_a_flawed_picture(
    monkeypatch: pytest.MonkeyPatch, wrong_run: Path, tmp_path: Path, flaw: str, said: str
) -> None:
    built = build_report([wrong_run], tmp_path / "good", registry=_registry(), n_boot=10)
    assert "data:image/png;base64," in built.files["html"].read_text()  # the scene was drawn
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    with pytest.raises(PluginBug) as info:
        build_report([wrong_run], tmp_path / "report", registry=_registry(), n_boot=10)
    assert str(info.value) == f"{ORIGIN}: {FAMILY}: {said}"


@pytest.mark.parametrize(("flaw", "said"), PICTURE_FLAWS)
def test_bpb_view_names_a_flawed_picture(
    monkeypatch: pytest.MonkeyPatch, wrong_run: Path, flaw: str, said: str
) -> None:
    viewer = Viewer.load([wrong_run], _registry())
    scene_id = json.loads(next(wrong_run.rglob("balls.json")).read_text())["scene_id"]
    assert viewer.overlay(0, scene_id, "balls").startswith(b"\x89PNG")
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    with pytest.raises(PluginBug) as info:
        viewer.overlay(0, scene_id, "balls")
    assert str(info.value) == f"{ORIGIN}: {FAMILY}: {said}"


def test_bpb_simulate_is_one_line_naming_the_family_plugin_and_exit_3(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, flawed_data: Path
) -> None:
    source = Path(support.flawed_family.__file__).read_text()
    install("bpb-flawed", "1.2", {"flawed_family": source}, {"flawed": "flawed_family"})
    monkeypatch.setenv("BPB_TEST_FLAW", "ground_truths_short")
    many = [str(flawed_data)] * 128  # 256 scenes: in batches of CHUNK
    done = run_bpb("simulate", *many, "--simulator", "flawed-analytic", "--workers", "1")
    assert done.returncode == 3
    assert done.stdout == ""  # no line paired with the wrong scene file
    said = f"ground_truths() returned a list of {CHUNK - 1} for {CHUNK} scenes; expected a list"
    said += " with one"
    debug = "(set BPB_DEBUG=1 for a traceback)"
    assert done.stderr.strip().splitlines() == [
        f"error: {ORIGIN}: {FAMILY}: {said} ground truth per scene {debug}"
    ]


READ_BACK_FLAWS = [
    ("load_config_raise", "load_config() raised ValueError: load_config exploded"),
    ("load_config_type", "load_config() returned dict; expected DatasetConfig (the family's "
     "config_model)"),
    ("simulator_name_type", "simulator_name() returned None; expected a simulator's name (str)"),
]  # fmt: skip


@pytest.mark.parametrize("model", ["oracle", "vision"])
@pytest.mark.parametrize(("flaw", "said"), READ_BACK_FLAWS)
def test_the_oracle_and_vision_asked_without_a_simulator_name_a_flawed_family(
    monkeypatch: pytest.MonkeyPatch, flawed_data: Path, model: str, flaw: str, said: str
) -> None:
    """A request naming no simulator (an adapter asked from Python: ModelRequest's simulator is
    optional) takes the family's default one. The oracle and vision asked the family's
    load_config(None) and simulator_name() unchecked: the ValueError itself, an AttributeError of
    the dict, or bad input ("unknown simulator None") blamed on the user."""
    registry = _registry()
    scene = next(iter(load_dataset(flawed_data, registry=registry)))
    messages = build_messages("balls", scene, registry=registry)
    request = ModelRequest(messages, "balls", scene=scene.state, family="flawed")
    reply = asyncio.run(registry.adapter(f"baseline:{model}").complete(request))
    assert json.loads(reply.text) == {"balls": len(scene.truth.predictions)}
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    with pytest.raises(PluginBug) as info:
        asyncio.run(registry.adapter(f"baseline:{model}").complete(request))
    assert str(info.value) == f"{ORIGIN}: {FAMILY}: {said}"


@pytest.mark.parametrize("command", ["simulate", "run"])
@pytest.mark.parametrize(("flaw", "said"), READ_BACK_FLAWS)
def test_reading_a_dataset_s_config_back_is_one_line_naming_the_family_plugin_and_exit_3(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, flawed_data: Path,
    tmp_path: Path, command: str, flaw: str, said: str,
) -> None:  # fmt: skip
    """bpb simulate and bpb run read the dataset's config back with the family's load_config()
    and ask its simulator_name(), unchecked: "internal error: ValueError: ..." naming no plugin,
    an AttributeError of the dict, or a dataset blamed for naming simulator None."""
    source = Path(support.flawed_family.__file__).read_text()
    install("bpb-flawed", "1.2", {"flawed_family": source}, {"flawed": "flawed_family"})
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    out = str(tmp_path / "run")
    args = {
        "simulate": ["simulate", str(flawed_data)],
        "run": ["run", "--data", str(flawed_data), "--adapter", "baseline:stasis", "--out", out],
    }[command]
    done = run_bpb(*args)
    assert done.returncode == 3
    assert done.stderr.strip().splitlines() == [
        f"error: {ORIGIN}: {FAMILY}: {said} (set BPB_DEBUG=1 for a traceback)"
    ]
    assert done.stdout == ""


@pytest.mark.parametrize(("flaw", "said"), PREDICT_FLAWS[:2])
def test_bpb_run_with_a_baseline_is_one_line_naming_the_family_plugin_and_exit_3(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, flawed_data: Path,
    tmp_path: Path, flaw: str, said: str,
) -> None:  # fmt: skip
    """The baseline read the family's predictors unchecked: a str was offered letter by letter,
    as bad input (exit 2: "offers no such prediction; known: baseline:oracle, baseline:s, ...").
    A predictors property that raised escaped isinstance(family, Predicting) itself on Python
    3.11 (whose runtime protocols read data members with hasattr): a raw traceback."""
    source = Path(support.flawed_family.__file__).read_text()
    install("bpb-flawed", "1.2", {"flawed_family": source}, {"flawed": "flawed_family"})
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    out = tmp_path / "run"
    done = run_bpb("run", "--data", str(flawed_data), "--adapter", "baseline:stasis",
                   "--out", str(out), "--tasks", "balls")  # fmt: skip
    assert done.returncode == 3
    assert done.stderr.strip().splitlines() == [
        f"error: {ORIGIN}: {FAMILY}: {said} (set BPB_DEBUG=1 for a traceback)"
    ]
    assert not out.exists()


def test_bpb_run_with_vision_names_a_perceive_of_the_wrong_type_and_exit_3(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, flawed_data: Path, tmp_path: Path
) -> None:
    """baseline:vision ran the family's ground_truth() on whatever perceive() returned: a dict
    was blamed on ground_truth() ("raised AttributeError: 'dict' object has no attribute ...")."""
    source = Path(support.flawed_family.__file__).read_text()
    install("bpb-flawed", "1.2", {"flawed_family": source}, {"flawed": "flawed_family"})
    monkeypatch.setenv("BPB_TEST_FLAW", "perceive_type")
    done = run_bpb("run", "--data", str(flawed_data), "--adapter", "baseline:vision",
                   "--out", str(tmp_path / "run"), "--tasks", "balls", "--limit", "1")  # fmt: skip
    assert done.returncode == 3
    assert "Traceback" not in done.stderr  # above the error: the progress line only
    assert done.stderr.strip().splitlines()[-1] == (
        f"error: {ORIGIN}: {FAMILY}: {PERCEIVE_TYPE} (set BPB_DEBUG=1 for a traceback)"
    )


def test_bpb_report_is_one_line_naming_the_family_plugin_and_exit_3(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, wrong_run: Path, tmp_path: Path
) -> None:
    source = Path(support.flawed_family.__file__).read_text()
    install("bpb-flawed", "1.2", {"flawed_family": source}, {"flawed": "flawed_family"})
    monkeypatch.setenv("BPB_TEST_FLAW", "picture_raise")
    done = run_bpb("report", str(wrong_run), "--out", str(tmp_path / "report"), "--bootstrap", "10")
    assert done.returncode == 3
    assert done.stderr.strip().splitlines() == [
        f"error: {ORIGIN}: {FAMILY}: picture() raised RuntimeError: picture exploded "
        "(set BPB_DEBUG=1 for a traceback)"
    ]
