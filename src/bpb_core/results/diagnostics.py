"""Diagnostics the paper describes only in prose, derived from the results frames.

Confusion tables and the stasis index look at *answered* units only: a unit the model did not
label (missing answer, API or parse error, duplicate or invalid label) says nothing about what it
believes. Positive means ``T`` (a contact happened).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from bpb_core.results.tables import RUN_COLUMNS

DEFAULT_TOLERANCES = (0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0)
"""Tolerances of :func:`tolerance_curve`, in ball radii (1.0 is the Q3 rule)."""


def _labelled(units: pd.DataFrame, tasks: tuple[str, ...]) -> pd.DataFrame:
    frame = units[units["task"].isin(tasks)]
    valid = (frame["status"] == "ok") & ~frame["duplicate"] & frame["pred"].isin(["T", "F"])
    return frame[valid]


def _rates(counts: pd.DataFrame) -> pd.DataFrame:
    tp, fp, fn = counts["tp"], counts["fp"], counts["fn"]
    precision = tp / (tp + fp).where(tp + fp > 0)
    recall = tp / (tp + fn).where(tp + fn > 0)
    f1 = 2 * precision * recall / (precision + recall).where(precision + recall > 0)
    return counts.assign(precision=precision, recall=recall, f1=f1)


def confusion(units: pd.DataFrame) -> pd.DataFrame:
    """Confusion counts with precision, recall and F1 for Q1 (all balls) and Q2 (per wall).

    Returns:
        Columns ``run, adapter, model, baseline, task, unit, tp, fp, fn, tn, precision,
        recall, f1``; ``unit`` is ``all`` for Q1 and the wall name (or ``all``) for Q2.
        Precision/recall/F1 are NaN when undefined (no positives).
    """
    frame = _labelled(units, ("q1", "q2"))
    truth = frame["truth"] == "T"
    pred = frame["pred"] == "T"
    flags = pd.DataFrame(
        {
            "tp": truth & pred,
            "fp": ~truth & pred,
            "fn": truth & ~pred,
            "tn": ~truth & ~pred,
        }
    ).astype("int64")
    keyed = pd.concat([frame[[*RUN_COLUMNS, "task", "unit"]], flags], axis=1)
    pooled = keyed.assign(unit="all")
    walls = keyed[keyed["task"] == "q2"]
    both = pd.concat([pooled, walls], ignore_index=True)
    counts = both.groupby([*RUN_COLUMNS, "task", "unit"], observed=True).sum().reset_index()
    return _rates(counts)


def stasis_index(units: pd.DataFrame) -> pd.DataFrame:
    """How often a model predicts that nothing happens when something does.

    Returns:
        One row per run: ``contact_stasis`` (share of true Q1 and Q2 contacts labelled ``F``),
        ``q1_stasis`` and ``q2_stasis`` (the same per task), ``motion_stasis`` (share of balls
        that truly moved more than one radius, or were pocketed, that are predicted within one
        radius of where they started), and the counts ``contacts`` and ``moved`` behind them.
    """
    labels = _labelled(units, ("q1", "q2"))
    labels = labels[labels["truth"] == "T"].assign(missed=lambda f: f["pred"] == "F")
    per_task = labels.pivot_table(
        index=RUN_COLUMNS, columns="task", values="missed", aggfunc="mean", observed=True
    ).reindex(columns=["q1", "q2"])
    pooled = labels.groupby(RUN_COLUMNS, observed=True)["missed"].agg(["mean", "size"])
    moves = _moved_units(units)
    motion = moves.groupby(RUN_COLUMNS, observed=True)["unmoved"].agg(["mean", "size"])
    out = pd.DataFrame(
        {
            "contact_stasis": pooled["mean"],
            "q1_stasis": per_task["q1"],
            "q2_stasis": per_task["q2"],
            "motion_stasis": motion["mean"],
            "contacts": pooled["size"],
            "moved": motion["size"],
        }
    )
    out[["contacts", "moved"]] = out[["contacts", "moved"]].fillna(0).astype("int64")
    return out.reset_index()


def _moved_units(units: pd.DataFrame) -> pd.DataFrame:
    """Answered Q3 units (position or null) of balls that truly moved more than R or were
    pocketed."""
    frame = units[(units["task"] == "q3") & (units["status"] == "ok") & ~units["duplicate"]]
    frame = frame[frame["pred"].isin(["pos", "null"])]
    travelled = np.hypot(frame["truth_x"] - frame["start_x"], frame["truth_y"] - frame["start_y"])
    moved = (frame["truth"] == "null") | (travelled > frame["radius"])
    frame = frame[moved]
    shift = np.hypot(frame["pred_x"] - frame["start_x"], frame["pred_y"] - frame["start_y"])
    return frame.assign(unmoved=shift <= frame["radius"])  # a null prediction (NaN) moved


def distance_errors(units: pd.DataFrame, *, by_horizon: bool = False) -> pd.DataFrame:
    """Q3 position error (m) where both prediction and truth are positions.

    Returns:
        Columns ``run, adapter, model, baseline[, horizon], mean, median, p90, max, n,
        null_mismatch`` (``null_mismatch``: answered balls where exactly one side is null).
    """
    keys = [*RUN_COLUMNS, "horizon"] if by_horizon else list(RUN_COLUMNS)
    frame = units[(units["task"] == "q3") & (units["status"] == "ok")]
    both = frame[frame["distance"].notna()]
    stats = both.groupby(keys, observed=True)["distance"].agg(
        mean="mean", median="median", p90=lambda d: d.quantile(0.9), max="max", n="size"
    )
    mismatch = (frame["truth"] == "null") != (frame["pred"] == "null")
    mismatch &= frame["pred"].isin(["pos", "null"])
    counts = mismatch.groupby([frame[k] for k in keys], observed=True).sum()
    stats["null_mismatch"] = counts.reindex(stats.index).fillna(0).astype("int64")
    return stats.reset_index()


def tolerance_curve(
    units: pd.DataFrame, tolerances: tuple[float, ...] = DEFAULT_TOLERANCES
) -> pd.DataFrame:
    """Q3 accuracy (strict, pooled over balls) if a ball counted as right within k radii.

    Returns:
        Columns ``run, adapter, model, baseline, tolerance`` (in radii), ``tolerance_m``
        (metres, for the first row's radius) and ``accuracy``. At ``tolerance == 1`` this is
        the Q3 per-ball accuracy pooled over all scenes.
    """
    frame = units[units["task"] == "q3"]
    ok = ((frame["status"] == "ok") & ~frame["duplicate"]).to_numpy(dtype=bool)
    both_null = ((frame["truth"] == "null") & (frame["pred"] == "null")).to_numpy(dtype=bool)
    ratio = (frame["distance"] / frame["radius"]).to_numpy(dtype=float)
    ks = np.asarray(tolerances, dtype=float)
    hits = ok[:, None] & (both_null[:, None] | (ratio[:, None] <= ks[None, :]))
    wide = pd.DataFrame(hits, columns=ks, index=frame.index)
    wide[RUN_COLUMNS] = frame[RUN_COLUMNS]
    means = wide.groupby(RUN_COLUMNS, observed=True)[list(ks)].mean()
    long = means.melt(ignore_index=False, var_name="tolerance", value_name="accuracy")
    long = long.reset_index().sort_values(["run", "tolerance"], kind="stable")
    radius = float(frame["radius"].iloc[0]) if len(frame) else float("nan")
    long["tolerance"] = long["tolerance"].astype("float64")
    long.insert(len(RUN_COLUMNS) + 1, "tolerance_m", long["tolerance"] * radius)
    return long.reset_index(drop=True)


def usage(calls: pd.DataFrame) -> pd.DataFrame:
    """Tokens (incl. reasoning), cost, latency, retries and failures per run.

    ``cost`` sums the calls whose cost is known; ``cost_unknown`` counts the others (NaN cost
    is never read as 0). Missing calls (no answer file) are counted, not measured.
    """
    made = calls[calls["status"] != "missing"]
    grouped = made.groupby(RUN_COLUMNS, observed=True)
    out = grouped.agg(
        calls=("status", "size"),
        input_tokens=("input_tokens", "sum"),
        output_tokens=("output_tokens", "sum"),
        reasoning_tokens=("reasoning_tokens", "sum"),
        cached_tokens=("cached_tokens", "sum"),
        cost=("cost", lambda c: c.sum(min_count=1)),
        cost_unknown=("cost", lambda c: int(c.isna().sum())),
        latency_mean=("latency", "mean"),
        latency_median=("latency", "median"),
        retries=("retries", "sum"),
    )
    status = calls.groupby([*RUN_COLUMNS, "status"], observed=True).size().unstack(fill_value=0)
    for name in ("ok", "parse_error", "api_error", "missing"):
        out[name] = (
            status[name].reindex(out.index).fillna(0).astype("int64") if name in status else 0
        )
    out["tokens_per_call"] = (out["input_tokens"] + out["output_tokens"]) / out["calls"]
    return out.reset_index()
