"""The failure gallery: the worst answered scenes, with truth and prediction drawn on the scene.

Which scenes: per run, the answered scenes with the lowest score (weighted by the first suite
whose tasks the scene was asked, else the mean over its tasks). What is shown comes from the
plugins: the scene family draws the scene (:class:`~bpb_core.capabilities.Picturing`), each
task's scorer marks truth and prediction on it (:class:`~bpb_core.capabilities.DrawsOverlay`) and
says in words what was wrong (:class:`~bpb_core.capabilities.ExplainsErrors`). Core only chooses
the scenes and lays them out.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import pandas as pd

from bpb_core.capabilities import DrawsOverlay, ExplainsErrors, Picturing
from bpb_core.errors import blamed
from bpb_core.layout import SceneKey
from bpb_core.picture import ScenePicture
from bpb_core.plugin_calls import returned
from bpb_core.run_folder import REPLIED
from bpb_core.scored_units import object_origin

if TYPE_CHECKING:
    from bpb_core.interfaces import Scorer
    from bpb_core.results.frames import Results
    from bpb_core.results.reading import RunFolder

SCORE = "score"


@dataclass(frozen=True)
class Case:
    """One gallery entry: which run and scene, its scores, what was wrong per task, the image."""

    run: str
    scene_id: str
    horizon: float
    scores: dict[str, float]
    wrong: dict[str, list[str]] = field(default_factory=dict)
    png: bytes = b""


def worst_cases(results: Results, count: int = 8) -> pd.DataFrame:
    """Up to ``count`` answered (run, scene) pairs with the lowest score.

    Runs take turns (models before baselines, each run's worst scene first), so one bad run
    does not fill the gallery; only scenes answered in every task and not fully right qualify.
    Equal scores keep scene order (horizon, then index).
    """
    wide = scene_totals(results)
    # ties in scene order, (horizon, index): the id's numbers as numbers (h3_9999 before
    # h3_10000, h3 before h10), not the id's text
    wide = wide[wide[SCORE] < 1.0].sort_values([SCORE, "horizon", "index"], kind="stable")
    wide["turn"] = wide.groupby("run", observed=True).cumcount()
    ranked = wide.sort_values(["turn", "baseline", SCORE, "run"], kind="stable")
    return ranked.head(count).drop(columns="turn").reset_index(drop=True)


def scene_totals(results: Results) -> pd.DataFrame:
    """One row per fully answered (run, scene): each task's score and ``score``, the weighted
    score of the first suite whose tasks the scene was asked (else the mean over its tasks)."""
    scenes, suites = results.scenes, results.suites
    wide = scenes.pivot_table(
        index=["run", "baseline", "horizon", "index", "scene_id"],
        columns="task",
        values="score",
        observed=True,
    )
    wide.columns.name = None
    answered = scenes.assign(ok=scenes["status"].isin(REPLIED))
    all_ok = answered.groupby(["run", "horizon", "index"], observed=True)["ok"].all()
    wide = wide.reset_index()
    keys = pd.MultiIndex.from_frame(wide[["run", "horizon", "index"]])
    wide = wide[all_ok.reindex(keys).fillna(False).to_numpy(dtype=bool)].copy()
    tasks = sorted(str(t) for t in scenes["task"].unique())
    score = pd.Series(float("nan"), index=wide.index)
    for suite in suites:
        if not set(suite.weights) <= set(wide.columns):
            continue
        asked = wide[list(suite.weights)].notna().all(axis=1) & score.isna()
        weighted = sum(w * wide[t] for t, w in suite.weights.items())
        score = score.where(~asked, weighted)
    mean = wide[[t for t in tasks if t in wide.columns]].mean(axis=1)
    wide[SCORE] = score.fillna(mean)
    return wide


def build_cases(
    results: Results,
    scorers: Mapping[str, Scorer],
    count: int = 8,
    origins: Mapping[str, str] | None = None,
) -> list[Case]:
    """Gallery cases for the worst scenes of ``results``, drawn and explained by the plugins.

    Args:
        origins: Who supplied each task's scorer (``Registered.origin``), for one-line errors.

    Raises:
        PluginBug: A scorer's ``explain`` or ``overlay`` raised or returned the wrong type.
    """
    runs = {run.label: run for run in results.runs}
    units = results.units
    cases = []
    for row in worst_cases(results, count).to_dict(orient="records"):
        run, sid = runs[str(row["run"])], str(row["scene_id"])
        rows = units[(units["run"] == run.label) & (units["scene_id"] == sid)]
        key = SceneKey(float(row["horizon"]), int(row["index"]))
        tasks = [t for t in results.tasks if t in row and not pd.isna(row[t])]
        scores = {t: float(row[t]) for t in tasks} | {SCORE: float(row[SCORE])}
        by_task = {t: rows[rows["task"] == t] for t in tasks}
        wrong = {
            t: _explain(scorer, _origin(origins, t), by_task[t]) for t in tasks
            if isinstance(scorer := scorers[t], ExplainsErrors)
        }  # fmt: skip
        png = drawing(run, key, by_task, scorers, origins)
        cases.append(Case(run.label, sid, key.horizon, scores, wrong, png))
    return cases


def drawing(
    run: RunFolder,
    key: SceneKey,
    rows: Mapping[str, pd.DataFrame],
    scorers: Mapping[str, Scorer],
    origins: Mapping[str, str] | None = None,
) -> bytes:
    """The family's picture of the scene with every task's overlay; empty when the family
    draws nothing.

    Raises:
        PluginBug: A scorer's ``overlay`` raised, naming who supplied it (``origins``).
    """
    if not isinstance(run.family, Picturing):
        return b""
    scene, _ = run.truth(key)
    picture = _picture(run.family, run, key, scene)
    for task, task_rows in rows.items():
        scorer = scorers[task]
        if isinstance(scorer, DrawsOverlay):
            with blamed(_origin(origins, task), f"scorer {_name(scorer)!r}: overlay()"):
                scorer.overlay(picture, task_rows)
    return picture.png()


def _picture(family: Picturing, run: RunFolder, key: SceneKey, scene: Any) -> ScenePicture:
    """The run's family's ``picture``, checked: a :class:`~bpb_core.picture.ScenePicture`."""
    origin = run.family_origin or object_origin(family)
    what = f"scene family {_name(family)!r}: picture()"
    with blamed(origin, what):
        picture = family.picture(run.dataset, key.dir(run.dataset), scene)
    if isinstance(picture, ScenePicture):
        return picture
    raise returned(origin, what, type(picture).__name__, "bpb_core.ScenePicture")


def _origin(origins: Mapping[str, str] | None, task: str) -> str:
    return (origins or {}).get(task, f"the scorer of task {task!r}")


def _name(scorer: object) -> str:
    return str(getattr(scorer, "name", type(scorer).__name__))


def _explain(scorer: ExplainsErrors, origin: str, rows: pd.DataFrame) -> list[str]:
    """``scorer.explain(rows)``, checked: a list of strings."""
    what = f"scorer {_name(scorer)!r}: explain()"
    with blamed(origin, what):
        lines = scorer.explain(rows)
    if isinstance(lines, list | tuple) and all(isinstance(line, str) for line in lines):
        return list(lines)
    shown = repr(lines)
    raise returned(origin, what, shown if len(shown) <= 80 else shown[:77] + "...", "a list of str")
