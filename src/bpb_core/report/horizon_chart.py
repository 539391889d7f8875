"""Accuracy by horizon in the paper's form: grouped bars per task, one group per horizon, one bar
per run (a colour-blind-safe colour per model, greys and hatches for the baselines), every bar
labelled with its value.

Completeness is drawn, not hidden: a cell under 100% answered carries a ``*`` after its value;
a cell under the threshold is drawn as a pale outline labelled "left out" with its answered
share, so a stopped run never reads as "accuracy falls with horizon".
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from bpb_core.report.charts import figure, label, png, run_styles
from bpb_core.results.completeness import level

if TYPE_CHECKING:
    from bpb_core.registry import SuiteInfo

SHORT_FACE = "#f0f0f0"


def suite_by_horizon(accuracy: pd.DataFrame, suite: SuiteInfo) -> pd.DataFrame:
    """A suite's weighted accuracy per (run, horizon), with the least complete task's
    completeness (empty when a task of it is absent)."""
    keys = ["run", "baseline", "horizon"]
    cells = accuracy.assign(run=accuracy["run"].astype(str)).set_index([*keys, "task"])
    wide = cells["accuracy"].unstack("task")  # keeps cells with no answer (NaN): drawn left out
    done = cells["completeness"].unstack("task")
    if not set(suite.weights) <= set(wide.columns):
        return pd.DataFrame(columns=[*keys, "accuracy", "completeness"])
    out = pd.DataFrame({"accuracy": sum(w * wide[t] for t, w in suite.weights.items())})
    out["completeness"] = done[list(suite.weights)].min(axis=1)
    return out.reset_index()


def accuracy_by_horizon(
    accuracy: pd.DataFrame,
    order: Sequence[str],
    suites: Sequence[SuiteInfo] = (),
    titles: Mapping[str, str] | None = None,
    *,
    min_complete: float = 0.9,
    view: str = "answered only",
) -> bytes:
    """One panel per task (and per suite): grouped bars by horizon, one bar per run in
    ``order``."""
    titles = titles or {}
    panels = {str(t): accuracy[accuracy["task"] == t] for t in sorted(accuracy["task"].unique())}
    for suite in suites:
        panels[suite.name] = suite_by_horizon(accuracy, suite)
    horizons = sorted(float(h) for h in accuracy["horizon"].unique())
    runs = [r for r in order if r in set(accuracy["run"].astype(str))]
    wide = len(runs) * len(horizons) > 14
    ncols = 1 if wide or len(panels) == 1 else 2
    nrows = (len(panels) + ncols - 1) // ncols
    width = 7.0 if ncols == 1 else 3.5 * ncols
    fig, axes = figure(nrows, ncols, (width, 2.6 * nrows + 0.5 + 0.18 * len(runs)))
    styles = run_styles(accuracy[["run", "baseline"]])
    for ax in list(axes.flat)[len(panels) :]:
        ax.set_visible(False)
    for ax, (name, data) in zip(axes.flat, panels.items(), strict=False):
        _panel(ax, data, runs, horizons, styles, min_complete)
        ax.set_title(titles.get(name, name), fontsize=9)
    fig.suptitle(f"Accuracy by horizon ({view})", fontsize=10)
    handles = [_handle(styles[r], label(r, _is_baseline(accuracy, r))) for r in runs]
    fig.legend(
        handles=handles, loc="outside lower center", ncols=min(len(runs), 3), fontsize=7,
        title=f"* under 100% answered; pale = under {100 * min_complete:.0f}%, left out",
        title_fontsize=7, frameon=False,
    )  # fmt: skip
    return png(fig)


def _is_baseline(accuracy: pd.DataFrame, run: str) -> bool:
    return bool(accuracy.loc[accuracy["run"] == run, "baseline"].iloc[0])


def _handle(style: dict[str, Any], text: str) -> Any:
    from matplotlib.patches import Patch

    return Patch(facecolor=style["color"], hatch=style["hatch"], edgecolor="white", label=text)


def _panel(
    ax: Any,
    data: pd.DataFrame,
    runs: Sequence[str],
    horizons: Sequence[float],
    styles: dict[str, dict[str, Any]],
    min_complete: float,
) -> None:
    width = 0.84 / max(len(runs), 1)
    many = len(runs) * len(horizons) > 10
    for k, run in enumerate(runs):
        chosen = data[data["run"] == run].to_dict(orient="records")
        rows = {float(r["horizon"]): dict(r) for r in chosen}
        for j, horizon in enumerate(horizons):
            if horizon in rows:
                x = j - 0.42 + width * (k + 0.5)
                _bar(ax, x, width, rows[horizon], styles[run], min_complete, many)
    ax.set_xticks(range(len(horizons)), [f"{h:g} s" for h in horizons], fontsize=8)
    ax.set_xlim(-0.5, len(horizons) - 0.5)
    ax.set_ylim(0, 118 if many else 112)
    ax.set_yticks([0, 25, 50, 75, 100])
    ax.tick_params(axis="y", labelsize=7)
    ax.set_ylabel("accuracy (%)", fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    ax.set_axisbelow(True)


def _bar(
    ax: Any,
    x: float,
    width: float,
    cell: Mapping[Any, Any],
    style: dict[str, Any],
    min_complete: float,
    many: bool,
) -> None:
    value = 100 * float(cell["accuracy"])
    done = float(cell["completeness"]) if not np.isnan(cell["completeness"]) else 0.0
    grade = level(done, min_complete)
    text_args: dict[str, Any] = {"ha": "center", "va": "bottom", "fontsize": 5.5 if many else 7}
    if many:
        text_args["rotation"] = 90
    if grade == "short" or np.isnan(value):
        ax.bar(x, 100, width, facecolor=SHORT_FACE, edgecolor=style["color"], ls=":", lw=0.6)
        text = f"left out ({100 * done:.0f}% ans.)"
        ax.text(x, 2, text, color="#666666", **{**text_args, "rotation": 90, "fontsize": 5.5})
        return
    bar = ax.bar(x, value, width, color=style["color"], edgecolor="white", lw=0.4)[0]
    bar.set_hatch(style["hatch"])
    if value == 0:  # a zero is a value: a stub on the axis, not an empty slot
        ax.plot([x - width / 2, x + width / 2], [0.6, 0.6], color=style["color"], lw=2.5)
    mark = "*" if grade == "partial" else ""
    ax.text(x, value + 1, f"{value:.0f}{mark}", **text_args)
