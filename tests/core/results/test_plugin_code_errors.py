"""A plugin's scorer or diagnostic that raises, or returns the wrong type, is one PluginBug
naming the plugin (not an internal error from deep inside pandas).

The same checks guard every caller of a scorer: load_results and bpb report, the library's
score_answer and mark, and bpb view (the gallery's explain and overlay too);
before, the last ones called the scorer unchecked. A report's task_metrics (a scorer that
ReportsMetrics) was unchecked too: a list or a frame without the metric columns came out as an
internal TypeError or KeyError; so was its metric_notes (a list, or notes that are not strings,
failed deep in the report's exports or pages)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pandas as pd
import pytest

from bpb_core import (
    DiagnosticInfo,
    ModelResponse,
    ParseFailure,
    ScorerInfo,
    TaskInfo,
    UnitRow,
    Usage,
    hookimpl,
    load_dataset,
    score_answer,
)
from bpb_core.errors import PluginBug
from bpb_core.library import mark
from bpb_core.registry import PluginSource, make_registry
from bpb_core.report.build import build_report, report_parts
from bpb_core.results import load_results
from bpb_core.runner import RunOptions, run_eval
from bpb_core.web.viewer import Viewer
from bpb_tasks.questions.question import BilliardsQuestion

FLAW = {"now": ""}
ORIGIN = "plugin 'faulty' (faulty_hooks) from bpb-faulty 1.2"


class CountTask(BilliardsQuestion):
    name: ClassVar[str] = "brk"
    default_cot: ClassVar[bool] = False
    title: ClassVar[str] = "Broken"

    def example(self, scene: Any) -> str:
        return json.dumps({"n": 0})

    def question(self, scene: Any, options: Any) -> str:
        return f"Say n.\n{self.example(scene)}"

    def validate(self, value: Any, scene: Any) -> dict[str, Any]:
        if not isinstance(value, dict) or "n" not in value:
            raise ParseFailure("need n")
        return {"n": value["n"]}

    def expected(self, truth: Any) -> dict[str, Any]:
        return {"n": 0}


class FlawedScorer:
    name = "brk"
    task = "brk"

    @property
    def scene_rule(self) -> str:
        return "All" if FLAW["now"] == "rule_typo" else "mean"

    @property
    def columns(self) -> Any:
        return ["n"] if FLAW["now"] == "columns_type" else {}

    def units(self, answer: Any, truth: Any, scene: Any) -> Any:
        if FLAW["now"] == "units_raise":
            raise RuntimeError("units exploded")
        if FLAW["now"] == "units_type":
            return {"n": 1}
        return [UnitRow("n", "0", None if answer is None else str(answer["n"]))]

    def score(self, units: pd.DataFrame) -> Any:
        same = units["pred"] == units["truth"]
        if FLAW["now"] == "score_type":
            return same
        return pd.DataFrame({"correct": same, "distance": np.nan}, index=units.index)

    def explain(self, rows: pd.DataFrame) -> Any:
        if FLAW["now"] == "explain_raise":
            raise RuntimeError("explain exploded")
        if FLAW["now"] == "explain_type":
            return "n is wrong"
        return ["n is wrong"]

    def overlay(self, picture: Any, rows: pd.DataFrame) -> None:
        if FLAW["now"] == "overlay_raise":
            raise RuntimeError("overlay exploded")

    @property
    def metric_notes(self) -> Any:
        if FLAW["now"] == "notes_type":
            return ["n_share"]
        if FLAW["now"] == "notes_values":
            return {"n_share": 0.5}
        return {"n_share": "the share of n right"}

    def task_metrics(self, units: pd.DataFrame) -> Any:
        if FLAW["now"] == "metrics_raise":
            raise RuntimeError("metrics exploded")
        if FLAW["now"] == "metrics_type":
            return [0.5]
        runs = units[["run", "adapter", "model", "baseline"]].drop_duplicates()
        if FLAW["now"] == "metrics_columns":
            return runs
        return runs.assign(n_share=0.5)


class FlawedDiagnostic:
    name = "brk_diag"
    title = "Broken diagnostic"
    terminal = ()

    @property
    def percent(self) -> Any:
        return "n_share" if FLAW["now"] == "percent_str" else ()

    def table(self, results: Any) -> Any:
        if FLAW["now"] == "table_raise":
            raise RuntimeError("table exploded")
        if FLAW["now"] == "table_type":
            return [1, 2]
        return pd.DataFrame({"run": [], "adapter": [], "model": [], "baseline": []})


class Faulty:
    @hookimpl
    def bpb_eval_tasks(self) -> list[TaskInfo]:
        return [TaskInfo("brk", lambda: CountTask, family="billiards")]

    @hookimpl
    def bpb_scorers(self) -> list[ScorerInfo]:
        return [ScorerInfo("brk", lambda: FlawedScorer, task="brk")]

    @hookimpl
    def bpb_diagnostics(self) -> list[DiagnosticInfo]:
        return [DiagnosticInfo("brk_diag", lambda: FlawedDiagnostic, tasks=("brk",))]


@pytest.fixture
def answered(dataset: Path, tmp_path: Path) -> tuple[Any, Path]:
    registry = make_registry(
        [(Faulty(), PluginSource("faulty", "bpb-faulty", "1.2", "faulty_hooks"))]
    )
    FLAW["now"] = ""
    run = tmp_path / "run"
    # built by this registry, the oracle knows "brk" (it looked tasks up in the installed
    # plugins only, so a library caller's local task stopped the run as unknown)
    oracle = registry.adapter("baseline:oracle")
    run_eval(dataset, oracle, run, RunOptions(tasks=("brk",), limit=1), registry=registry)
    return registry, run


def test_the_oracle_built_by_a_registry_answers_that_registry_s_tasks(
    answered: tuple[Any, Path],
) -> None:
    statuses = [json.loads(p.read_text())["status"] for p in answered[1].rglob("brk.json")]
    assert statuses and set(statuses) == {"ok"}


@pytest.mark.parametrize(
    ("flaw", "said"),
    [
        ("units_raise", "scorer 'brk': units() raised RuntimeError: units exploded"),
        ("units_type", "scorer 'brk': units() returned {'n': 1}; expected a list of bpb_core."),
        ("score_type", "scorer 'brk': score() returned Series; expected a DataFrame with the "),
    ],
)
def test_a_flawed_scorer_is_named(answered: tuple[Any, Path], flaw: str, said: str) -> None:
    registry, run = answered
    FLAW["now"] = flaw
    with pytest.raises(PluginBug) as info:
        load_results([run], registry=registry)
    assert str(info.value).startswith(f"{ORIGIN}: {said}")


@pytest.mark.parametrize(
    ("flaw", "said"),
    [
        ("table_raise", "diagnostic 'brk_diag': table() raised RuntimeError: table exploded"),
        ("table_type", "diagnostic 'brk_diag': table() returned list; expected a pandas DataFrame"),
        # before: read letter by letter, so no column showed as a percentage, without a word
        ("percent_str", "diagnostic 'brk_diag': percent is 'n_share'; expected a tuple of "
         "column names (str)"),
    ],
)  # fmt: skip
def test_a_flawed_diagnostic_is_named(answered: tuple[Any, Path], flaw: str, said: str) -> None:
    registry, run = answered
    results = load_results([run], registry=registry)
    FLAW["now"] = flaw
    with pytest.raises(PluginBug) as info:
        report_parts(results, registry, n_boot=10)
    assert str(info.value) == f"{ORIGIN}: {said}"


@pytest.mark.parametrize(
    ("flaw", "said"),
    [
        ("metrics_raise", "task_metrics() raised RuntimeError: metrics exploded"),
        ("metrics_type", "task_metrics() returned list; expected a DataFrame with the columns "
         "run, adapter, model, baseline, n_share"),
        ("metrics_columns", "task_metrics() returned a DataFrame with columns ['run', 'adapter', "
         "'model', 'baseline']; expected a DataFrame with the columns run, adapter, model, "
         "baseline, n_share"),
    ],
)  # fmt: skip
def test_a_flawed_task_metrics_is_named(answered: tuple[Any, Path], flaw: str, said: str) -> None:
    registry, run = answered
    results = load_results([run], registry=registry)
    good = report_parts(results, registry, n_boot=10)[0].tables["brk_metrics"]
    assert good["n_share"].eq(0.5).all()
    FLAW["now"] = flaw
    with pytest.raises(PluginBug) as info:
        report_parts(results, registry, n_boot=10)
    assert str(info.value) == f"{ORIGIN}: scorer 'brk': {said}"


@pytest.mark.parametrize(
    ("flaw", "said"),
    [
        ("notes_type", "metric_notes is ['n_share']; expected a dict of metric column (str) -> "
         "one line (str)"),
        ("notes_values", "metric_notes is {'n_share': 0.5}; expected a dict of metric column "
         "(str) -> one line (str)"),
    ],
)  # fmt: skip
def test_a_report_names_flawed_metric_notes(
    answered: tuple[Any, Path], tmp_path: Path, flaw: str, said: str
) -> None:
    registry, run = answered
    good = build_report([run], tmp_path / "good", registry=registry, n_boot=10)
    assert "the share of n right" in good.files["html"].read_text()
    FLAW["now"] = flaw
    with pytest.raises(PluginBug) as info:
        build_report([run], tmp_path / "report", registry=registry, n_boot=10)
    assert str(info.value) == f"{ORIGIN}: scorer 'brk': {said}"
    assert not (tmp_path / "report").exists()


SCORER_FLAWS = [
    ("units_raise", "scorer 'brk': units() raised RuntimeError: units exploded"),
    ("units_type", "scorer 'brk': units() returned {'n': 1}; expected a list of bpb_core."),
    ("score_type", "scorer 'brk': score() returned Series; expected a DataFrame with the "),
]
ATTRIBUTE_FLAWS = [
    ("rule_typo", "scorer 'brk': scene_rule is 'All'; expected 'mean' or 'all'"),
    ("columns_type", "scorer 'brk': columns is ['n']; expected a dict of column name (str) -> "
     "pandas dtype (str)"),
]  # fmt: skip


@pytest.mark.parametrize(("flaw", "said"), ATTRIBUTE_FLAWS)
def test_a_scorer_with_an_unusable_scene_rule_or_columns_is_named(
    answered: tuple[Any, Path], small_dataset: Path, flaw: str, said: str
) -> None:
    """A scene_rule other than mean or all was scored as mean without a word (a typo'd "All"
    gave a wrong score); columns that are not a dict failed deep in pandas."""
    registry, run = answered
    scene = load_dataset(small_dataset, registry=registry)["h1_0000"]
    FLAW["now"] = flaw
    with pytest.raises(PluginBug) as info:
        load_results([run], registry=registry)
    assert str(info.value) == f"{ORIGIN}: {said}"
    with pytest.raises(PluginBug) as info:
        score_answer("brk", scene, '{"n": 0}', registry=registry)
    assert str(info.value) == f"{ORIGIN}: {said}"
    with pytest.raises(PluginBug) as info:
        mark(FlawedScorer(), {"n": 0}, "ok", scene)
    assert str(info.value) == f"module {__name__!r}: {said}"


@pytest.mark.parametrize(("flaw", "said"), SCORER_FLAWS)
def test_score_answer_names_a_flawed_scorer(
    answered: tuple[Any, Path], small_dataset: Path, flaw: str, said: str
) -> None:
    registry, _ = answered
    scene = load_dataset(small_dataset, registry=registry)["h1_0000"]
    assert score_answer("brk", scene, '{"n": 0}', registry=registry).score == 1.0
    FLAW["now"] = flaw
    with pytest.raises(PluginBug) as info:
        score_answer("brk", scene, '{"n": 0}', registry=registry)
    assert str(info.value).startswith(f"{ORIGIN}: {said}")


def test_mark_names_the_module_of_a_flawed_scorer_object(
    answered: tuple[Any, Path], small_dataset: Path
) -> None:
    registry, _ = answered
    scene = load_dataset(small_dataset, registry=registry)["h1_0000"]
    FLAW["now"] = "score_type"
    with pytest.raises(PluginBug) as info:
        mark(FlawedScorer(), {"n": 0}, "ok", scene)
    assert str(info.value).startswith(f"module {__name__!r}: scorer 'brk': score() returned")


class WrongAnswers:
    name = "wrong:n"

    async def complete(self, request: Any) -> ModelResponse:
        return ModelResponse('{"n": 1}', Usage(), None, 0.0, "wrong")


@pytest.mark.parametrize(
    ("flaw", "said"),
    [
        ("explain_raise", "scorer 'brk': explain() raised RuntimeError: explain exploded"),
        ("explain_type", "scorer 'brk': explain() returned 'n is wrong'; expected a list of str"),
        ("overlay_raise", "scorer 'brk': overlay() raised RuntimeError: overlay exploded"),
    ],
)
def test_the_gallery_names_a_flawed_explain_or_overlay(
    answered: tuple[Any, Path], dataset: Path, tmp_path: Path, flaw: str, said: str
) -> None:
    registry, _ = answered
    run = tmp_path / "wrong"
    options = RunOptions(tasks=("brk",), limit=1)
    run_eval(dataset, WrongAnswers(), run, options, registry=registry)
    FLAW["now"] = flaw
    with pytest.raises(PluginBug) as info:
        build_report([run], tmp_path / "report", registry=registry, n_boot=10)
    assert str(info.value) == f"{ORIGIN}: {said}"


def test_bpb_view_names_a_flawed_overlay(answered: tuple[Any, Path]) -> None:
    registry, run = answered
    viewer = Viewer.load([run], registry)
    FLAW["now"] = "overlay_raise"
    with pytest.raises(PluginBug) as info:
        viewer.overlay(0, "h1_0000", "brk")
    assert (
        str(info.value)
        == f"{ORIGIN}: scorer 'brk': overlay() raised RuntimeError: overlay exploded"
    )
