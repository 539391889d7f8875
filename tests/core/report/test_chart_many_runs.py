"""Charts of the paper's sweep: 17 models and 4 baselines stay apart and readable.

The by-horizon chart and the leaderboards are drawn for 21 runs with long names and their text
boxes measured with matplotlib's own renderer: no two value labels, run names or legend entries
overlap, and the figure widens with the number of bars instead of squeezing them.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg

from bpb_core.registry import SuiteInfo
from bpb_core.report.charts import (
    by_horizon_figure,
    leaderboard_figure,
    run_styles,
)

MODELS = [
    f"litellm:{name}"
    for name in (
        "gpt-5.5", "gpt-5.4-pro", "gpt-5.4", "gpt-5.4-mini", "o4-deep-research",
        "claude-opus-4.7", "claude-sonnet-4.6", "claude-haiku-4.5", "gemini-3.1-pro-preview",
        "gemini-3-flash-preview", "gemini-2.5-flash-lite", "grok-4.1", "qwen3-vl-235b-a22b",
        "llama-4-maverick", "mistral-medium-3.2", "glm-4.6v", "kimi-k2.5-vision",
    )
]  # fmt: skip
BASELINES = ["baseline:oracle", "baseline:random", "baseline:stasis", "baseline:straight"]
HORIZONS = [1.0, 2.0, 3.0, 4.0, 5.0]
TASKS = ["q1", "q2", "q3"]


def accuracy_frame(models: list[str], baselines: list[str]) -> pd.DataFrame:
    rng = np.random.default_rng(7)
    rows = [
        {
            "run": run, "baseline": run in baselines, "horizon": h, "task": task,
            "accuracy": float(rng.choice([0.0, 1.0, rng.uniform(0.05, 0.99)])),
            "completeness": 1.0,
        }
        for run in [*models, *baselines]
        for h in HORIZONS
        for task in TASKS
    ]  # fmt: skip
    return pd.DataFrame(rows)


def boxes(fig: Any, texts: list[Any]) -> list[Any]:
    renderer = fig.canvas.get_renderer()
    return [t.get_window_extent(renderer) for t in texts if t.get_visible() and t.get_text()]


def overlapping(extents: list[Any]) -> list[tuple[int, int]]:
    """Pairs of boxes that share more than half a pixel each way."""
    found = []
    for (i, a), (j, b) in itertools.combinations(enumerate(extents), 2):
        dx = min(a.x1, b.x1) - max(a.x0, b.x0)
        dy = min(a.y1, b.y1) - max(a.y0, b.y0)
        if dx > 0.5 and dy > 0.5:
            found.append((i, j))
    return found


def drawn(fig: Any) -> Any:
    FigureCanvasAgg(fig)
    fig.draw_without_rendering()
    return fig


def test_styles_stay_distinct_for_24_models_and_8_baselines() -> None:
    runs = pd.DataFrame(
        {"run": [f"m{k:02d}" for k in range(24)] + [f"b{k}" for k in range(8)],
         "baseline": [False] * 24 + [True] * 8}
    )  # fmt: skip
    styles = run_styles(runs)
    bars = {(s["color"], s["hatch"]) for s in styles.values()}
    lines = {(s["color"], str(s["ls"]), s["marker"]) for s in styles.values()}
    assert len(bars) == len(styles) == 32
    assert len(lines) == 32


def test_by_horizon_chart_of_21_runs_has_no_overlapping_labels() -> None:
    accuracy = accuracy_frame(MODELS, BASELINES)
    suite = SuiteInfo(name="total", weights={"q1": 0.4, "q2": 0.3, "q3": 0.3})
    order = [*MODELS, *BASELINES]
    fig = drawn(by_horizon_figure(accuracy, order, [suite]))
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert len(panels) == 4
    for ax in panels:
        values = boxes(fig, list(ax.texts))
        assert len(values) == len(order) * len(HORIZONS)
        assert overlapping(values) == [], ax.get_title()
        assert overlapping(boxes(fig, ax.get_xticklabels())) == []
    (legend,) = fig.legends
    entries = boxes(fig, legend.get_texts())
    assert len(entries) == len(order)
    assert overlapping(entries) == []
    small = by_horizon_figure(accuracy_frame(MODELS[:2], BASELINES[:2]), order)
    assert fig.get_figwidth() > 1.5 * small.get_figwidth()  # grows with the bars


def test_leaderboard_of_21_runs_has_no_overlapping_names_or_values() -> None:
    accuracy = accuracy_frame(MODELS, BASELINES)
    board = (
        accuracy.groupby(["run", "baseline", "task"])["accuracy"].mean().unstack("task")
    ).reset_index()
    fig = drawn(leaderboard_figure(board, TASKS))
    for ax in (ax for ax in fig.axes if ax.get_visible()):
        names = boxes(fig, ax.get_yticklabels())
        assert len(names) == len(board)
        assert overlapping(names) == []
        assert overlapping(boxes(fig, list(ax.texts))) == []
