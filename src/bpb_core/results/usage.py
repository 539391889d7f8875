"""Tokens (incl. reasoning), cost, latency, retries and failures per run, from the calls frame."""

from __future__ import annotations

import pandas as pd

from bpb_core.results.tables import RUN_COLUMNS


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
