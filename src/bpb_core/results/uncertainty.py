"""Uncertainty: bootstrap confidence intervals over scenes, paired comparisons of two runs, and
published figures beside the runs of their models.

Scenes are resampled with replacement within each horizon (the leaderboard score is a mean
over horizons, so each horizon keeps its size), and the same resampled scenes are used for every
task, so a suite's interval accounts for scenes being shared by its tasks. Resampling is
done with multinomial weights and one matrix product per horizon: fully vectorised. Generators
are seeded from ``seed`` and the run label, so results do not depend on the order of runs.

Published figures (:func:`reference_table`): each score a reference states for a model, next to
the score of every run of that model on the same scenes. A run's figure is the strict score (an
unanswered scene counts as wrong, as a missing answer does in a published table) with its
bootstrap interval, over the reference's horizons for a mean and over one horizon for a
per-horizon figure. A figure the run cannot be compared on (it has no scenes at a horizon the
figure covers) keeps the stated value and says why the run's is blank; a task the run did not
ask gives no row. Rows of runs that answered only part of the scenes say how much.
"""

from __future__ import annotations

import math
import warnings
import zlib
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from bpb_core.errors import BadInput
from bpb_core.registry import Figure, ReferenceInfo, SuiteInfo, model_key
from bpb_core.results.tables import RUN_COLUMNS, UNANSWERED, View, scene_scores, tasks_of

FloatArray = np.ndarray[tuple[int, ...], np.dtype[np.float64]]


def _rng(seed: int, *labels: str) -> np.random.Generator:
    return np.random.default_rng([seed, *(zlib.crc32(label.encode()) for label in labels)])


def score_matrix(
    units: pd.DataFrame,
    run: str,
    suites: Sequence[SuiteInfo] = (),
    view: View = "strict",
    scenes: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """Scene scores of one run: index (horizon, scene_id), one column per task of ``units``
    (NaN = left out of the view or not asked) plus one per suite (its weighted scene score).
    ``scenes``: the :func:`~bpb_core.results.tables.scene_scores` of ``units``, if computed."""
    tasks = tasks_of(units)
    scenes = scene_scores(units) if scenes is None else scenes
    scenes = scenes[scenes["run"] == run]
    if view == "answered":
        scenes = scenes.assign(score=scenes["score"].mask(scenes["status"].isin(UNANSWERED)))
    wide = scenes.pivot_table(
        index=["horizon", "scene_id"], columns="task", values="score", observed=True, dropna=False
    ).reindex(columns=tasks)
    for suite in suites:
        wide[suite.name] = sum(w * wide[t] for t, w in suite.weights.items())
    wide.columns.name = None
    return wide[[*tasks, *(s.name for s in suites)]]


def _horizon_means(
    matrix: pd.DataFrame,
    tasks: list[str],
    suites: Sequence[SuiteInfo],
    rng: np.random.Generator | None,
    n_boot: int,
) -> tuple[FloatArray, FloatArray]:
    """(point estimate per metric, bootstrap replicates B x metrics): means over horizons.

    A suite is the weighted sum of its task means (as in the leaderboard), not a mean of
    per-scene suite scores, so both views agree with
    :func:`~bpb_core.results.tables.leaderboard`.
    """
    points, reps = [], []
    for _, block in matrix[tasks].groupby(level="horizon", sort=True):
        values = block.to_numpy(dtype=float)
        present = ~np.isnan(values)
        filled = np.where(present, values, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            points.append(filled.sum(0) / present.sum(0))
            if rng is not None:
                n = len(values)
                weights = rng.multinomial(n, np.full(n, 1.0 / n), size=n_boot).astype(float)
                reps.append((weights @ filled) / (weights @ present.astype(float)))
    width = len(tasks)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a task absent from a horizon
        point = np.nanmean(np.stack(points), axis=0) if points else np.full(width, np.nan)
        rep = np.nanmean(np.stack(reps), axis=0) if reps else np.full((1, width), np.nan)
    for suite in suites:
        idx = [tasks.index(t) for t in suite.weights]
        weights_vec = np.array(list(suite.weights.values()))
        point = np.append(point, point[idx] @ weights_vec)
        rep = np.column_stack([rep, rep[:, idx] @ weights_vec])
    return point, rep


def _interval(reps: FloatArray, level: float) -> tuple[FloatArray, FloatArray]:
    alpha = (1 - level) / 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        lo, hi = np.nanquantile(reps, [alpha, 1 - alpha], axis=0)
    return lo, hi


def bootstrap_ci(
    units: pd.DataFrame,
    suites: Sequence[SuiteInfo] = (),
    *,
    view: View = "strict",
    n_boot: int = 2000,
    seed: int = 0,
    level: float = 0.95,
    scenes: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """Leaderboard scores with bootstrap confidence intervals over scenes (``scenes``: as for
    :func:`score_matrix`).

    Returns:
        Columns ``run, adapter, model, baseline, metric, estimate, lo, hi, scenes``; ``metric``
        is a task or a suite.
    """
    rows = []
    tasks = tasks_of(units)
    names = [*tasks, *(s.name for s in suites)]
    runs = units[RUN_COLUMNS].drop_duplicates().to_dict(orient="records")
    scenes = scene_scores(units) if scenes is None else scenes
    for info in runs:
        matrix = score_matrix(units, str(info["run"]), suites, view, scenes)
        point, reps = _horizon_means(matrix, tasks, suites, _rng(seed, str(info["run"])), n_boot)
        lo, hi = _interval(reps, level)
        for j, metric in enumerate(names):
            rows.append({**info, "metric": metric, "estimate": point[j], "lo": lo[j], "hi": hi[j]})
            rows[-1]["scenes"] = int(matrix[metric].notna().sum())
    columns = [*RUN_COLUMNS, "metric", "estimate", "lo", "hi", "scenes"]
    frame = pd.DataFrame(rows, columns=columns)
    return frame.astype({"estimate": "float64", "lo": "float64", "hi": "float64"})


def sign_test(wins: int, losses: int) -> float:
    """Two-sided exact sign test p-value (ties dropped); McNemar's exact test for 0/1 scores."""
    n = wins + losses
    if n == 0:
        return 1.0
    k = min(wins, losses)
    log_half = n * math.log(0.5)
    terms = [math.lgamma(n + 1) - math.lgamma(i + 1) - math.lgamma(n - i + 1) for i in range(k + 1)]
    tail = sum(math.exp(t + log_half) for t in terms)
    return min(1.0, 2 * tail)


def paired_comparison(
    units: pd.DataFrame,
    a: str,
    b: str,
    suites: Sequence[SuiteInfo] = (),
    *,
    view: View = "strict",
    n_boot: int = 2000,
    seed: int = 0,
    level: float = 0.95,
    scenes: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """Run ``a`` minus run ``b`` on the scenes both answered, per metric (``scenes``: as for
    :func:`score_matrix`).

    Raises:
        BadInput: The two runs answered different datasets (same scene ids, other scenes).

    Returns:
        One row per metric: ``a, b, metric, a_score, b_score, diff, lo, hi, scenes, wins,
        losses, ties, p_value`` (``diff`` = a - b as a mean over horizons; ``lo``/``hi`` its
        bootstrap interval; ``wins``/``losses`` count scenes where a scored higher/lower;
        ``p_value`` from the exact sign test on them).
    """
    datasets = {run: _datasets(units, run) for run in (a, b)}
    if datasets[a] != datasets[b]:
        raise BadInput(f"runs {a!r} and {b!r}: answered different datasets; nothing to pair")
    tasks = tasks_of(units)
    scenes = scene_scores(units) if scenes is None else scenes
    left, right = (score_matrix(units, run, suites, view, scenes) for run in (a, b))
    shared = left.index.intersection(right.index)
    diff = left.loc[shared] - right.loc[shared]
    left, right = left.loc[shared].where(diff.notna()), right.loc[shared].where(diff.notna())
    point, reps = _horizon_means(diff, tasks, suites, _rng(seed, a, b), n_boot)
    a_point, _ = _horizon_means(left, tasks, suites, None, 0)
    b_point, _ = _horizon_means(right, tasks, suites, None, 0)
    lo, hi = _interval(reps, level)
    names = [*tasks, *(s.name for s in suites)]
    counts = diff[names].notna().sum().to_numpy()
    wins, losses = (diff[names] > 0).sum().to_numpy(), (diff[names] < 0).sum().to_numpy()
    columns = {"a": a, "b": b, "metric": names, "a_score": a_point, "b_score": b_point}
    columns |= {"diff": point, "lo": lo, "hi": hi, "scenes": counts, "wins": wins}
    columns |= {"losses": losses, "ties": counts - wins - losses}
    columns["p_value"] = [sign_test(int(w), int(n)) for w, n in zip(wins, losses, strict=True)]
    return pd.DataFrame(columns)


def _datasets(units: pd.DataFrame, run: str) -> set[str]:
    return set(units.loc[units["run"] == run, "dataset"].astype(str).unique())


def all_pairs(
    units: pd.DataFrame,
    suites: Sequence[SuiteInfo] = (),
    runs: Sequence[str] | None = None,
    **kwargs: object,
) -> pd.DataFrame:
    """:func:`paired_comparison` of every pair of ``runs`` that answered the same dataset.

    By default: every pair of model (non-baseline) runs, then every model against every
    baseline; nothing when there is no model run.
    """
    if runs is None:
        models = sorted(units.loc[~units["baseline"], "run"].unique().tolist())
        baselines = sorted(units.loc[units["baseline"], "run"].unique().tolist())
        pairs = [(a, b) for i, a in enumerate(models) for b in models[i + 1 :]]
        pairs += [(a, b) for a in models for b in baselines]
    else:
        pairs = [(a, b) for i, a in enumerate(runs) for b in runs[i + 1 :]]
    pairs = [(a, b) for a, b in pairs if _datasets(units, a) == _datasets(units, b)]
    if kwargs.get("scenes") is None:  # computed once for all of them
        kwargs["scenes"] = scene_scores(units)
    frames = [paired_comparison(units, a, b, suites, **kwargs) for a, b in pairs]  # type: ignore[arg-type]
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


REFERENCE_COLUMNS = [
    "run", "reference", "model", "metric", "horizon", "estimate", "lo", "hi", "stated", "diff",
    "where", "note", "source",
]  # fmt: skip


def reference_table(
    units: pd.DataFrame,
    suites: Sequence[SuiteInfo],
    references: Sequence[ReferenceInfo],
    *,
    n_boot: int = 2000,
    seed: int = 0,
    scenes: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """One row per (model run, stated figure of its model): see the module docstring
    (``scenes``: the :func:`~bpb_core.results.tables.scene_scores` of ``units``, if computed).

    Returns:
        Columns :data:`REFERENCE_COLUMNS`; ``horizon`` NaN for a mean, ``estimate``/``lo``/``hi``/
        ``diff`` NaN where the run cannot be compared (``note`` says why).
    """
    rows: list[dict[str, Any]] = []
    scenes = scene_scores(units) if scenes is None else scenes
    models = units.loc[~units["baseline"].astype(bool), ["run", "adapter", "model"]]
    for run, adapter, model in models.drop_duplicates().itertuples(index=False):
        keys = {model_key(str(adapter)), model_key(str(model))}
        mine = units[units["run"] == run]
        scored = scenes[scenes["run"] == run]
        tasks = set(tasks_of(mine))
        metrics = tasks | {s.name for s in suites if set(s.weights) <= tasks}
        for reference in references:
            figures = [
                f for f in reference.figures if model_key(f.model) in keys and f.metric in metrics
            ]
            rows += _run_rows(str(run), mine, scored, suites, reference, figures, n_boot, seed)
    return pd.DataFrame(rows, columns=REFERENCE_COLUMNS).astype({c: "float64" for c in _NUMBERS})


_NUMBERS = ("horizon", "estimate", "lo", "hi", "stated", "diff")


def _run_rows(
    run: str,
    units: pd.DataFrame,
    scenes: pd.DataFrame,
    suites: Sequence[SuiteInfo],
    reference: ReferenceInfo,
    figures: Sequence[Figure],
    n_boot: int,
    seed: int,
) -> list[dict[str, Any]]:
    """The rows of one run against one reference's figures of its model."""
    have = {round(float(h), 9) for h in units["horizon"].unique().tolist()}
    rows = []
    for span in dict.fromkeys(_span(f, reference) for f in figures):
        missing = sorted(set(span) - have)
        sub = units[units["horizon"].round(9).isin(span)]
        scored = scenes[scenes["horizon"].round(9).isin(span)]
        scores: dict[str, Any] = {}
        if not missing:
            ci = bootstrap_ci(sub, suites, n_boot=n_boot, seed=seed, scenes=scored)
            values = ci[["estimate", "lo", "hi"]].to_numpy(dtype=float).tolist()
            scores = dict(zip(ci["metric"].astype(str), map(tuple, values), strict=True))
        note = _note(missing, scored["status"])
        for figure in (f for f in figures if _span(f, reference) == span):
            rows.append(_row(run, reference, figure, scores.get(figure.metric), note))
    return rows


def _span(figure: Figure, reference: ReferenceInfo) -> tuple[float, ...]:
    """The horizons a figure is over (rounded so that 1 and 1.0000000001 are one horizon)."""
    spans = reference.horizons if figure.horizon is None else (figure.horizon,)
    return tuple(round(float(h), 9) for h in spans)


def _note(missing: Sequence[float], status: pd.Series) -> str:
    """Why a run's figure is blank, or how much of its scenes it answered (``status``: of each
    scene score)."""
    if missing:
        listed = ", ".join(f"{h:g}" for h in missing)
        return f"not comparable: the run has no scenes at horizon {listed} s"
    answered = float((~status.isin(UNANSWERED)).mean()) if len(status) else 0.0
    return "" if answered >= 1 else f"{answered:.0%} answered (unanswered count as wrong)"


def _row(
    run: str,
    reference: ReferenceInfo,
    figure: Figure,
    score: tuple[float, float, float] | None,
    note: str,
) -> dict[str, Any]:
    estimate, lo, hi = score if score is not None else (np.nan, np.nan, np.nan)
    return {
        "run": run,
        "reference": reference.name,
        "model": figure.model,
        "metric": figure.metric,
        "horizon": np.nan if figure.horizon is None else figure.horizon,
        "estimate": estimate,
        "lo": lo,
        "hi": hi,
        "stated": figure.value,
        "diff": estimate - figure.value,
        "where": figure.where,
        "note": note,
        "source": reference.source,
    }
