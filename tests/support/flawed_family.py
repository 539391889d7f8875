"""A third-party plugin whose scene family breaks its contract on demand: the billiards family
renamed ``flawed``, with one task and scorer about it.

``BPB_TEST_FLAW`` (read at each call, so a test sets it in its own environment or that of a
``bpb`` subprocess) picks the flaw: ``predictors_type`` (one str, not a tuple),
``predictors_raise`` (reading it raises), ``predict_raise``, ``predict_type`` (a dict, not
the family's truth model), ``truth_type`` (the same from ``ground_truth``), ``picture_raise``,
``picture_type`` (PNG bytes, not a ScenePicture),
``perceive_raise`` (a RuntimeError, not the ValueError of an unreadable image),
``perceive_type`` (the scene read as a dict, not its scene model), ``perception_error_type``
(a list, not a dict),
``ground_truths_short`` (``bpb simulate``'s batches: one truth fewer than scenes, so every
truth would pair with the next file), ``ground_truths_type`` (dicts, not its truth model),
``unstable_reasons_type`` (ground truths read back whose ``unstable_reasons`` is a str);
and at generation ``load_config_raise``, ``load_config_type`` (a dict, not its config model)
(these two and ``simulator_name_type``, None, also where a dataset is read back),
``make_scene_raise`` and ``make_scene_type`` (the scene's truth, not the scene), both from the
second scene of a horizon on (the first is written), ``late_raise`` (``make_scene_raise`` from
the sixth scene on), ``files_type`` (a list of names), and
``write_stats_raise``, ``write_stats_type`` (a str, not a list of them), ``write_stats_missing``
(a path it never wrote), ``check_config_raise``, ``physics_raise``, ``physics_type`` (a NaN),
``new_tally_raise``, ``new_tally_type`` (a dict), the tally's ``tally_add_raise``,
``tally_summary_raise``, ``tally_summary_type`` (a list), ``tally_summary_nan`` and
``tally_summary_scenes`` (its own ``scenes``, a count bpb keeps), ``init_in_worker_raise``
(the constructor, in a pool's worker process only), ``simulator_init_raise`` (its config names
``flawed-analytic``, whose constructor raises), and with ``--calibrate``
``calibrate_horizon_raise``, ``apply_calibration_raise`` and ``apply_calibration_type`` (the
record and config swapped); and in ``bpb bench sim`` (whose reference and contestant are its
own simulator) ``bench_reference_type`` (None), ``bench_reference_raise`` (reading it raises),
``bench_contestants_type`` (one str, not a tuple),
``bench_scenes_raise``, ``bench_scenes_type`` (dicts, not scenes), ``compare_raise``,
``compare_no_error`` (no ``error`` key), ``compare_type`` (an ``error`` in words),
``events_type`` (a float), ``scaled_scene_raise`` and ``scaled_scene_type`` (a dict).
Its simulator ``flawed-analytic`` is the analytic one, for this family's scenes.
The module is self-contained: tests install its source as a real distribution.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import random
from collections.abc import Sequence
from pathlib import Path
from typing import Any, ClassVar

import pandas as pd

from bpb_core import (
    ParseFailure,
    SceneFamilyInfo,
    ScorerInfo,
    SimulatorInfo,
    TaskInfo,
    UnitRow,
    hookimpl,
)
from bpb_tasks.billiards.family import BilliardsFamily, BilliardsTally
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.questions.question import BilliardsQuestion
from bpb_tasks.simulators.analytic.engine import AnalyticSimulator


def _flaw() -> str:
    return os.environ.get("BPB_TEST_FLAW", "")


class ReasonsAsText(FinalState):
    @property
    def unstable_reasons(self) -> Any:
        return "q1"  # a str, not a list of them


class FileNames:
    """A made scene whose files() are its file names alone."""

    def __init__(self, made: Any) -> None:
        self.truth, self.row, self._made = made.truth, made.row, made

    def files(self, images: bool) -> Any:
        return list(self._made.files(images))


class FlawedTally(BilliardsTally):
    def add(self, row: Any) -> None:
        if _flaw() == "tally_add_raise":
            raise RuntimeError("add exploded")
        super().add(row)

    def summary(self) -> Any:
        if _flaw() == "tally_summary_raise":
            raise RuntimeError("summary exploded")
        summary = super().summary()
        flawed = {
            "tally_summary_type": list(summary),
            "tally_summary_nan": {**summary, "collision_rate": math.nan},
            "tally_summary_scenes": {**summary, "scenes": self.scenes},
        }
        return flawed.get(_flaw(), summary)


class FlawedFamily(BilliardsFamily):
    name = "flawed"
    bench_description = "billiards scenes with flaws on demand"

    @property  # type: ignore[misc]
    def bench_reference(self) -> Any:
        if _flaw() == "bench_reference_raise":
            raise RuntimeError("bench_reference exploded")
        return None if _flaw() == "bench_reference_type" else "flawed-analytic:precision=50"

    @property  # type: ignore[misc]
    def bench_contestants(self) -> Any:
        return "flawed-analytic" if _flaw() == "bench_contestants_type" else ("flawed-analytic",)

    def bench_scenes(self, count: int, seed: int) -> Any:
        if _flaw() == "bench_scenes_raise":
            raise RuntimeError("bench_scenes exploded")
        scenes = super().bench_scenes(count, seed)
        return [s.model_dump() for s in scenes] if _flaw() == "bench_scenes_type" else scenes

    def compare(self, outcome: Any, reference: Any, scene: Any) -> Any:
        if _flaw() == "compare_raise":
            raise RuntimeError("compare exploded")
        measures = super().compare(outcome, reference, scene)
        if _flaw() == "compare_no_error":
            return {k: v for k, v in measures.items() if k != "error"}
        return {**measures, "error": "small"} if _flaw() == "compare_type" else measures

    def events(self, outcome: Any) -> Any:
        count = super().events(outcome)
        return count + 0.5 if _flaw() == "events_type" else count

    def scaled_scene(self, scene: Any, factor: float) -> Any:
        if _flaw() == "scaled_scene_raise":
            raise RuntimeError("scaled_scene exploded")
        busy = super().scaled_scene(scene, factor)
        return busy.model_dump() if _flaw() == "scaled_scene_type" else busy

    @property  # type: ignore[misc]
    def predictors(self) -> Any:
        if _flaw() == "predictors_raise":
            raise RuntimeError("predictors exploded")
        return "stasis" if _flaw() == "predictors_type" else BilliardsFamily.predictors

    @property  # type: ignore[misc]
    def truth_model(self) -> Any:
        return ReasonsAsText if _flaw() == "unstable_reasons_type" else FinalState

    def load_config(self, source: Any) -> Any:
        if _flaw() == "load_config_raise":
            raise ValueError("load_config exploded")
        config = super().load_config(source).model_copy(update={"family": self.name})
        return config.model_dump() if _flaw() == "load_config_type" else config

    def __init__(self) -> None:
        if _flaw() == "init_in_worker_raise" and multiprocessing.parent_process() is not None:
            raise RuntimeError("__init__ exploded in a worker")

    def check_config(self, config: Any, horizons: Sequence[float]) -> None:
        if _flaw() == "check_config_raise":
            raise RuntimeError("check_config exploded")
        super().check_config(config, horizons)

    def simulator_name(self, config: Any) -> Any:
        if _flaw() == "simulator_init_raise":
            return "flawed-analytic"
        return None if _flaw() == "simulator_name_type" else super().simulator_name(config)

    def physics(self, config: Any) -> Any:
        if _flaw() == "physics_raise":
            raise RuntimeError("physics exploded")
        physics = super().physics(config)
        return {**physics, "mu": math.nan} if _flaw() == "physics_type" else physics

    def new_tally(self, config: Any, horizon: float) -> Any:
        if _flaw() == "new_tally_raise":
            raise RuntimeError("new_tally exploded")
        tally = FlawedTally(**vars(super().new_tally(config, horizon)))
        return tally.summary() if _flaw() == "new_tally_type" else tally

    def calibrate_horizon(self, config: Any, simulator: Any, horizon: float) -> Any:
        if _flaw() == "calibrate_horizon_raise":
            raise RuntimeError("calibrate_horizon exploded")
        return super().calibrate_horizon(config, simulator, horizon)

    def apply_calibration(self, config: Any, results: Any) -> Any:
        if _flaw() == "apply_calibration_raise":
            raise RuntimeError("apply_calibration exploded")
        config, record = super().apply_calibration(config, results)
        return (record, config) if _flaw() == "apply_calibration_type" else (config, record)

    def make_scene(self, config: Any, simulator: Any, seed: int, horizon: float, index: int) -> Any:
        made = super().make_scene(config, simulator, seed, horizon, index)
        if index >= {"make_scene_raise": 1, "late_raise": 5}.get(_flaw(), index + 1):
            raise RuntimeError("make_scene exploded")
        if index >= 1 and _flaw() == "make_scene_type":
            return made.truth
        if _flaw() == "files_type":
            return FileNames(made)
        return made

    def write_stats(self, root: Path, config: Any, tallies: Any) -> Any:
        if _flaw() == "write_stats_raise":
            raise RuntimeError("write_stats exploded")
        written = super().write_stats(root, config, tallies)
        if _flaw() == "write_stats_missing":
            return [*written, "stats/never.png"]
        return written[0] if _flaw() == "write_stats_type" else written

    def predict(self, name: str, scene: Any, rng: random.Random) -> Any:
        if _flaw() == "predict_raise":
            raise RuntimeError("predict exploded")
        if _flaw() == "predict_type":
            return {"balls": []}
        return super().predict(name, scene, rng)

    def ground_truth(
        self, scene: Any, simulator: Any, horizon: float | None = None, *, stability: bool
    ) -> Any:
        if _flaw() == "truth_type":
            return {"balls": []}
        return super().ground_truth(scene, simulator, horizon, stability=stability)

    def ground_truths(
        self, scenes: Sequence[Any], simulator: Any, horizon: float | None = None
    ) -> Any:
        truths = super().ground_truths(scenes, simulator, horizon)
        if _flaw() == "ground_truths_type":
            return [truth.model_dump() for truth in truths]
        return truths[1:] if _flaw() == "ground_truths_short" else truths

    def perceive(self, image: bytes, prompt: str) -> Any:
        if _flaw() == "perceive_raise":
            raise RuntimeError("perceive exploded")
        scene = super().perceive(image, prompt)
        return scene.model_dump() if _flaw() == "perceive_type" else scene

    def perception_error(self, perceived: Any, scene: Any) -> Any:
        if _flaw() == "perception_error_type":
            return [0.5]
        return super().perception_error(perceived, scene)

    def picture(self, dataset: Path, folder: Path, scene: Any) -> Any:
        if _flaw() == "picture_raise":
            raise RuntimeError("picture exploded")
        if _flaw() == "picture_type":
            return b"\x89PNG"
        return super().picture(dataset, folder, scene)


class BallsTask(BilliardsQuestion):
    """How many balls are left: its expected answer reads the truth, as a real task's does."""

    name: ClassVar[str] = "balls"
    default_cot: ClassVar[bool] = False
    title: ClassVar[str] = "Balls"

    def example(self, scene: Any) -> str:
        return '{"balls": 7}'

    def question(self, scene: Any, options: Any) -> str:
        return f"How many balls are left?\n{self.example(scene)}"

    def validate(self, value: Any, scene: Any) -> dict[str, Any]:
        if not isinstance(value, dict) or not isinstance(value.get("balls"), int):
            raise ParseFailure("need an integer balls")
        return {"balls": value["balls"]}

    def expected(self, truth: Any) -> dict[str, Any]:
        return {"balls": len(truth.predictions)}


class BallsScorer:
    name = "balls"
    task = "balls"
    scene_rule = "mean"
    columns: ClassVar[dict[str, str]] = {}

    def units(self, answer: Any, truth: Any, scene: Any) -> list[UnitRow]:
        said = None if answer is None else str(answer["balls"])
        return [UnitRow("balls", str(len(truth.predictions)), said)]

    def score(self, units: pd.DataFrame) -> pd.DataFrame:
        same = units["pred"] == units["truth"]
        return pd.DataFrame({"correct": same, "distance": float("nan")}, index=units.index)


@hookimpl
def bpb_scene_families() -> list[SceneFamilyInfo]:
    return [SceneFamilyInfo("flawed", lambda: FlawedFamily, "Billiards with flaws on demand")]


class FlawedSimulator(AnalyticSimulator):
    def __init__(self, **options: Any) -> None:
        if _flaw() == "simulator_init_raise":
            raise RuntimeError("simulator __init__ exploded")
        super().__init__(**options)


@hookimpl
def bpb_simulators() -> list[SimulatorInfo]:
    info = SimulatorInfo("flawed-analytic", lambda: FlawedSimulator, "Analytic", family="flawed")
    return [info]


@hookimpl
def bpb_eval_tasks() -> list[TaskInfo]:
    return [TaskInfo("balls", lambda: BallsTask, family="flawed")]


@hookimpl
def bpb_scorers() -> list[ScorerInfo]:
    return [ScorerInfo("balls", lambda: BallsScorer, task="balls")]
