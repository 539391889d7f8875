"""Exports of one report part: every table as CSV, the paper's tables (the headline leaderboard
and accuracy by horizon, both answered only) as Markdown and LaTeX (booktabs), and the JSON
summary of ``bpb report --json``.

The Markdown and LaTeX tables show the same cells as the HTML page: a value under 100% answered
carries its answered share in brackets and a cell under the threshold reads "left out".
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from bpb_core.errors import writing
from bpb_core.report.sections import (
    Cell,
    Rows,
    different_conditions_note,
    different_scenes_note,
    headline_cells,
    horizon_cells,
    plain,
)
from bpb_core.results.completeness import incomplete_lines, unanswered_lines, unparsed_lines

if TYPE_CHECKING:
    from bpb_core.report.parts import Completeness, ReportPart


def paper_tables(part: ReportPart, rule: Completeness) -> dict[str, pd.DataFrame]:
    """The headline leaderboard, accuracy by horizon (answered only) and each task's metrics
    table as frames of text."""
    out = {
        "leaderboard": _frame(*headline_cells(part, rule)),
        "by_horizon": _frame(*horizon_cells(part.tables["accuracy_answered"], rule)),
    }
    for task, notes in part.metric_notes.items():
        table = part.tables[f"{task}_metrics"]
        columns = ["complete", *notes]
        rows: Rows = [
            (
                bool(row["baseline"]),
                [Cell(str(row["run"])), *(plain(row[c], True) for c in columns)],
            )
            for row in table.to_dict(orient="records")
        ]
        out[f"{task}_metrics"] = _frame(["run", *columns], rows)
    return out


def _frame(head: list[str], rows: Rows) -> pd.DataFrame:
    data = []
    for baseline, cells in rows:
        texts = [f"{c.text} ({c.note})" if c.note else c.text for c in cells]
        texts[0] += " (baseline)" if baseline else ""
        data.append(texts)
    return pd.DataFrame(data, columns=head, dtype="str")


def markdown(frame: pd.DataFrame) -> str:
    """A GitHub-flavoured Markdown table (first column left-aligned, the others right)."""

    def line(cells: list[str]) -> str:
        return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"

    align = [":---", *["---:"] * (len(frame.columns) - 1)]
    rows = [line([str(c) for c in frame.columns]), line(align)]
    rows += [line([str(v) for v in row]) for row in frame.itertuples(index=False)]
    return "\n".join(rows) + "\n"


def latex(frame: pd.DataFrame, caption: str) -> str:
    """A booktabs LaTeX table (``\\toprule``/``\\midrule``/``\\bottomrule``), text escaped."""
    styler = frame.style.hide(axis="index").format(escape="latex")
    styler = styler.format_index(escape="latex", axis=1)
    align = "l" + "r" * (len(frame.columns) - 1)
    caption = caption.replace("%", "\\%")
    return styler.to_latex(
        hrules=True, column_format=align, caption=caption, position="t", position_float="centering"
    )


def write_exports(part: ReportPart, out: Path, prefix: str, rule: Completeness) -> dict[str, Path]:
    """Every table as CSV under ``out/tables``, the paper's tables also as ``.md`` and
    ``.tex``."""
    files: dict[str, Path] = {}
    for name, frame in part.tables.items():
        path = out / "tables" / f"{prefix}{name}.csv"
        with writing(path):
            frame.to_csv(path, index=False)
        files[f"table:{prefix}{name}"] = path
    captions = {
        "leaderboard": "Leaderboard: mean accuracy over horizons, answered only (strict beside).",
        "by_horizon": "Accuracy by horizon, answered only (in brackets: the share answered).",
    }
    for name, frame in paper_tables(part, rule).items():
        captions.setdefault(name, f"{name.replace('_', ' ')}, answered only.")
        md = out / "tables" / f"{prefix}{name}.md"
        with writing(md):
            md.write_text(markdown(frame), encoding="utf-8")
        tex = out / "tables" / f"{prefix}{name}.tex"
        with writing(tex):
            tex.write_text(latex(frame, captions[name]), encoding="utf-8")
        files[f"markdown:{prefix}{name}"], files[f"latex:{prefix}{name}"] = md, tex
    return files


def records(frame: pd.DataFrame) -> list[dict[str, Any]]:
    """A frame as JSON-ready dicts (NaN as ``None``, numpy scalars as Python ones)."""
    cleaned = frame.astype(object).where(frame.notna(), None)
    out = []
    for row in cleaned.to_dict(orient="records"):
        out.append({str(k): v.item() if isinstance(v, np.generic) else v for k, v in row.items()})
    return out


def part_json(part: ReportPart) -> dict[str, Any]:
    """The JSON summary of one part (one dataset)."""
    tables, results = part.tables, part.results
    cells = ["run", "task", "horizon", "answered", "expected", "completeness", "level", "epochs"]
    by_horizon = tables["accuracy"].merge(
        tables["accuracy_answered"][["run", "task", "horizon", "accuracy", "scenes"]],
        on=["run", "task", "horizon"], suffixes=("_strict", "_answered"),
    )  # fmt: skip
    return {
        "dataset": part.dataset,
        "dataset_path": part.path,
        "scenes": part.scenes or None,
        "leaderboard": records(tables["summary"]),
        "leaderboard_answered": records(tables["leaderboard_answered"]),
        "suites": {s.name: dict(s.weights) for s in results.suites},
        "bootstrap": records(tables["bootstrap"]),
        "bootstrap_answered": records(tables["bootstrap_answered"]),
        "stable": records(tables["leaderboard_stable"]),
        "stable_exclusions": records(tables["stable_exclusions"]),
        "by_horizon": records(by_horizon),
        "completeness": records(tables["accuracy"][cells]),
        "incomplete": incomplete_lines(results),
        "unanswered": unanswered_lines(results),
        "unparsed": unparsed_lines(results),
        "different_scenes": different_scenes_note(part),
        "different_conditions": different_conditions_note(part),
        "usage": records(tables["usage"]),
        "pairs": records(tables["pairs"]),
        "references": records(tables["references"]),
        "metrics": {t: records(tables[f"{t}_metrics"]) for t in part.metric_notes},
        "metric_notes": {t: dict(notes) for t, notes in part.metric_notes.items()},
        "diagnostics": {d.name: records(tables[d.name]) for d in part.diagnostics},
    }
