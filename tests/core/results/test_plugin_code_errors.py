"""A plugin's scorer or diagnostic that raises, or returns the wrong type, is one PluginBug
naming the plugin (not an internal error from deep inside pandas)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pandas as pd
import pytest

from bpb_adapters.baseline.adapter import BaselineAdapter
from bpb_core import DiagnosticInfo, ParseFailure, ScorerInfo, TaskInfo, UnitRow, hookimpl
from bpb_core.errors import PluginBug
from bpb_core.registry import PluginSource, make_registry
from bpb_core.report.parts import report_parts
from bpb_core.results import load_results
from bpb_core.runner import RunOptions, run_eval
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
    scene_rule = "mean"
    columns: ClassVar[dict[str, str]] = {}

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


class FlawedDiagnostic:
    name = "brk_diag"
    title = "Broken diagnostic"
    percent = ()
    terminal = ()

    def table(self, results: Any) -> Any:
        if FLAW["now"] == "table_raise":
            raise RuntimeError("table exploded")
        return [1, 2]


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
    oracle = BaselineAdapter("baseline:oracle", "oracle", _registry=registry)  # knows "brk"
    run_eval(dataset, oracle, run, RunOptions(tasks=("brk",), limit=1), registry=registry)
    return registry, run


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
        ("", "diagnostic 'brk_diag': table() returned list; expected a pandas DataFrame"),
    ],
)
def test_a_flawed_diagnostic_is_named(answered: tuple[Any, Path], flaw: str, said: str) -> None:
    registry, run = answered
    results = load_results([run], registry=registry)
    FLAW["now"] = flaw
    with pytest.raises(PluginBug) as info:
        report_parts(results, registry, n_boot=10)
    assert str(info.value) == f"{ORIGIN}: {said}"
