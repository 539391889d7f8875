"""Scoring helpers of the tests: a scorer's units as a frame, and the Q1-Q3 rules applied one row
at a time (the reference the vectorised scorers are checked against)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from bpb_core.scored_units import SCORER_INPUT

_P_Q3 = [0.85, 0.08, 0.02, 0.05]
_P_LABEL = [0.3, 0.6, 0.05, 0.05]
Q3_COLUMNS = ("truth_x", "truth_y", "pred_x", "pred_y", "start_x", "start_y", "radius")


def unit_frame(
    scorer: Any, answer: Any, truth: Any, scene: Any, status: str = "ok"
) -> pd.DataFrame:
    """``scorer.units(...)`` as the frame ``score`` takes: base columns plus its own."""
    rows = scorer.units(answer, truth, scene)
    data: dict[str, Any] = {
        "status": status,
        "unit": [r.unit for r in rows],
        "truth": [r.truth for r in rows],
        "pred": [r.pred for r in rows],
        "duplicate": [r.duplicate for r in rows],
    }
    for position, name in enumerate(scorer.columns):
        data[name] = [r.values[position] for r in rows]
    return pd.DataFrame(data).astype({**SCORER_INPUT, **scorer.columns})


def correct_by_unit(
    scorer: Any, answer: Any, truth: Any, scene: Any, status: str = "ok"
) -> dict[str, bool]:
    """Unit name to whether the scorer marks it right."""
    frame = unit_frame(scorer, answer, truth, scene, status)
    result = scorer.score(frame)
    return {str(u): bool(c) for u, c in zip(frame["unit"], result["correct"], strict=True)}


def synthetic_units(task: str, rows: int, seed: int = 0) -> pd.DataFrame:
    """``rows`` random units of q1, q2 or q3 with a realistic mix of statuses, missing, invalid
    and duplicate predictions."""
    rng = np.random.default_rng([seed, rows, sum(map(ord, task))])
    status = rng.choice(["ok", "parse_error", "api_error"], rows, p=[0.9, 0.05, 0.05])
    if task == "q3":
        truth = rng.choice(["pos", "null"], rows, p=[0.9, 0.1])
        pred = rng.choice(np.array(["pos", "null", "?", None], dtype=object), rows, p=_P_Q3)
    else:
        truth = rng.choice(["T", "F"], rows, p=[0.3, 0.7])
        pred = rng.choice(np.array(["T", "F", "?", None], dtype=object), rows, p=_P_LABEL)
    data: dict[str, Any] = {
        "status": status,
        "unit": rng.integers(0, 7, rows).astype(str),
        "truth": truth,
        "pred": pred,
        "duplicate": rng.random(rows) < 0.01,
    }
    dtypes = dict(SCORER_INPUT)
    if task == "q3":
        tx, ty = rng.uniform(0.03, 1.97, rows), rng.uniform(0.03, 0.97, rows)
        px, py = tx + rng.normal(0, 0.03, rows), ty + rng.normal(0, 0.03, rows)
        is_pos, pred_pos = truth == "pos", pred == "pos"
        data |= {
            "truth_x": np.where(is_pos, tx, np.nan),
            "truth_y": np.where(is_pos, ty, np.nan),
            "pred_x": np.where(pred_pos, px, np.nan),
            "pred_y": np.where(pred_pos, py, np.nan),
            "start_x": tx,
            "start_y": ty,
            "radius": np.full(rows, 0.028575),
        }
        dtypes |= dict.fromkeys(Q3_COLUMNS, "float64")
    return pd.DataFrame(data).astype(dtypes)


def loop_correct(frame: pd.DataFrame, task: str) -> list[bool]:
    """The Q1-Q3 rules, one row at a time."""
    out = []
    for row in frame.itertuples():
        ok = row.status == "ok" and not row.duplicate
        if task == "q3":
            both_null = row.truth == "null" and row.pred == "null"
            d = ((row.pred_x - row.truth_x) ** 2 + (row.pred_y - row.truth_y) ** 2) ** 0.5
            out.append(ok and (both_null or bool(d <= row.radius)))
        else:
            out.append(ok and row.pred == row.truth)
    return out
