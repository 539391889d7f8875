"""What ``bpb run`` prints: the live progress rows (one per adapter and task), the table of
what a dry run would send (from :mod:`bpb_core.runner.dry_run`), and the summary of scores at
the end (from :mod:`bpb_core.results`)."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress as RichBar, TextColumn
from rich.table import Column, Table

from bpb_core.cli.console import stderr, stdout
from bpb_core.cli.fit import Name, print_fitted
from bpb_core.errors import BpbError
from bpb_core.runner import slug
from bpb_core.runner.dry_run import TYPICAL_OUTPUT, DryRun, dry_run, plus
from bpb_core.runner.options import ProgressEvent

if TYPE_CHECKING:
    import pandas as pd
    from rich.progress import TaskID

    from bpb_core.cli.run_file import Prepared
    from bpb_core.dataset.reader import DataFolder
    from bpb_core.registry import Registry
    from bpb_core.runner.options import RunOptions, RunResult


FAILED = ("parse_error", "refused", "cut", "empty", "api_error")
"""Final statuses other than ``ok`` of a pair that was sent."""
_SHORT = {"parse_error": "parse", "api_error": "api"}
_ALWAYS = ("parse_error", "api_error")  # shown even at 0; the rest only once they happen


@dataclass
class _Row:
    task_id: TaskID
    counts: Counter[str] = field(default_factory=Counter)  # by event kind and final status
    cost: float | None = 0.0

    def fields(self) -> dict[str, Any]:
        n, cost = self.counts, "$?" if self.cost is None else f"${self.cost:.4f}"
        failed = sum(n[s] for s in FAILED)
        kinds = ", ".join(f"{_SHORT.get(s, s)} {n[s]}" for s in FAILED if n[s] or s in _ALWAYS)
        text = f"ok {n['ok']} failed {failed} ({kinds}) retrying {n['retry']} "
        text += f"tok {n['tokens']:,} {cost}"
        if n["skipped"]:
            text += f" | {n['skipped']} done before"
        if n["not_sent"]:
            text += f" | {n['not_sent']} not sent"
        return {"stats": text}


class RichProgress:
    """Draws :class:`~bpb_core.runner.options.ProgressEvent` s as rich progress bars."""

    def __init__(self, bar: RichBar) -> None:
        self._bar = bar
        self._rows: dict[tuple[str, str], _Row] = {}

    def update(self, event: ProgressEvent) -> None:
        """Apply one event to its row (a warning is printed above the bars)."""
        if event.kind == "warning":
            text = escape(f"{event.adapter}: {event.reason}")
            self._bar.console.print(f"[yellow]warning:[/] {text}")
            return
        key = (event.adapter, event.task)
        if key not in self._rows:
            name = escape(f"{event.adapter} {event.task}")
            self._rows[key] = _Row(self._bar.add_task(name, total=0, stats=""))
        row = self._rows[key]
        n = row.counts
        if event.kind == "done":
            n[event.status or "ok"] += 1
            n["tokens"] += event.tokens
            if row.cost is not None:
                row.cost = None if event.cost is None else row.cost + event.cost
        else:  # planned, skipped (done before), retry
            n[event.kind] += event.count
        finished = n["ok"] + sum(n[s] for s in FAILED) + n["not_sent"]
        self._bar.update(row.task_id, total=n["planned"], completed=finished, **row.fields())


def make_bar() -> RichBar:
    """A rich progress bar on stderr with the run's columns."""
    return RichBar(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[stats]}"),
        console=stderr(),
        transient=False,
    )


def show_dry_run(
    data: DataFolder,
    out: Path,
    ready: list[Prepared],
    options: RunOptions,
    registry: Registry,
    *,
    pilot: bool = False,
) -> None:
    """Print, per adapter and task and in total, the calls a run would send, those already
    done, the estimated input tokens and USD, the output USD typical and at the cap, and the
    basis of each figure (nothing is sent). After ``--pilot`` it is the projection from the
    pilot's real usage."""
    title = "bpb run --pilot: projection from the pilot's real usage (not sent)"
    table = Table(
        Column("adapter", no_wrap=True, min_width=max(len(item.name) for item in ready)),
        "task", "calls", "done before", "input tokens", "input USD",
        "output USD typical", "output USD at cap", "projected USD",
        title=title if pilot else "bpb run --dry-run (nothing sent)",
    )  # fmt: skip
    sums: list[float | None] = [0.0, 0.0, 0.0, 0.0]
    notes = []
    for item in ready:
        plan = dry_run(data, out / slug(item.name), options, registry, item.adapter, item.origin)
        for task in options.tasks:
            row = plan.task(task)
            money = [row.input_cost, row.typical_output_cost, row.cap_output_cost, row.projected]
            sums = [plus(a, b) for a, b in zip(sums, money, strict=True)]
            table.add_row(
                escape(item.name), task, str(row.calls), str(row.done),
                f"{row.input_tokens:,}", *(_usd(v) for v in money),
            )  # fmt: skip
        notes.append(_basis(item.name, plan, options.tasks, out / slug(item.name)))
    table.add_row("total", "", "", "", "", *(_usd(v) for v in sums), end_section=True)
    stdout().print(table)
    for line in notes:
        stdout().print(escape(line), highlight=False, soft_wrap=True)


def _usd(value: float | None) -> str:
    return "no price" if value is None else f"${value:,.4f}"


def _basis(name: str, plan: DryRun, tasks: Iterable[str], folder: Path) -> str:
    """Where one adapter's figures come from: its count and prices, the output cap, and the
    typical output (the pairs already done, or the assumption before any)."""
    priced = plan.basis or "input ~ characters / 4 (the adapter cannot price a call)"
    seen = {t: plan.task(t).seen for t in tasks if plan.task(t).seen}
    if seen:
        each = ", ".join(f"{t} {n} at {plan.task(t).typical_tokens:,.0f}" for t, n in seen.items())
        typical = f"typical and projected: the real usage of pairs done in {folder} ({each} "
        typical += "output tokens per pair, re-asks included)"
    else:
        typical = f"typical: an assumed {TYPICAL_OUTPUT:,} output tokens per call, or the cap "
        typical += "if lower (no replies yet; --pilot N measures them)"
    return f"basis {name}: {priced}; {typical}"


def show_spending(results: Iterable[RunResult]) -> None:
    """Print, per capped run, what was spent (all sessions), reserved and left, and the pairs
    the cap kept from being sent."""
    for result in results:
        budget = result.budget
        if budget.get("cap") is None and budget.get("command_cap") is None:
            continue
        stderr().print(escape(spending_line(result.adapter, budget)), highlight=False)


def spending_line(adapter: str, budget: dict[str, Any]) -> str:
    """One line: spent, reserved and left under each cap, and the pairs the cap kept."""
    parts = [f"{adapter}: spent ${budget['spent']:.4f} (all sessions)"]
    if budget.get("cap") is not None:
        parts.append(f"its cap ${budget['cap']:.4f}, ${budget['left']:.4f} left")
    if budget.get("command_cap") is not None:
        parts.append(
            f"--max-cost ${budget['command_cap']:.4f} over the command: "
            f"${budget['command_spent']:.4f} spent, ${budget['command_left']:.4f} left"
        )
    parts.append(f"reserved ${budget['reserved']:.4f}")
    kept = budget.get("kept_by_cap") or []
    if kept:
        shown = ", ".join(kept[:5]) + (", ..." if len(kept) > 5 else "")
        parts.append(f"the cap kept {len(kept)} pairs from being sent ({shown})")
    return "; ".join(parts)


_NOT_SCORES = (
    "run", "adapter", "model", "baseline", "expected", "epochs", "completeness", "worst_cell",
)  # fmt: skip


def show_summary(
    run_dirs: list[Path], registry: Registry, folders: Iterable[DataFolder] = ()
) -> None:
    """Write ``scores.csv`` into each run folder and print the leaderboard summary
    (``folders``: the runs' datasets, already read)."""
    from bpb_core.results.frames import write_scores

    try:
        frame = write_scores(run_dirs, registry, folders)
    except BpbError as exc:
        stderr().print(f"[yellow]warning:[/] could not score the run: {exc}")
        return
    if frame is None or frame.empty:
        return
    _print_table(frame)
    for run, line in frame.attrs.get("warnings", []):
        stderr().print(f"[yellow]{escape(run)}: {escape(line)}[/]", highlight=False)
    parents = sorted({str(d.parent) for d in run_dirs})
    where = " ".join(parents) if parents else "RUN_DIR"
    stderr().print(
        f"next: bpb report {where} --out {parents[0] if parents else '.'}/report "
        "(charts, failure gallery, HTML)",
        highlight=False,
    )


def _print_table(frame: pd.DataFrame) -> None:
    """Answered-only scores and completeness first, the strict score beside each."""
    names = [
        c for c in frame.columns
        if c not in _NOT_SCORES and c != "short" and not c.endswith("_answered")
    ]  # fmt: skip
    rows = []
    for _, row in frame.iterrows():
        cells = [_pct(row["completeness"])]
        for name in names:
            answered, strict = row[f"{name}_answered"], row[name]
            if not math.isnan(float(answered)):
                cells.append(f"{_pct(answered)} ({_pct(strict)})")
            else:  # too incomplete, or not asked (a suite with a task the run lacks)
                cells.append("left out" if row["short"] else "–")
        cells.append(escape(str(row["short"])) or "–")
        rows.append((Name(str(row["adapter"])), cells))
    title = "bpb run: scores (answered only; strict in brackets)"
    print_fitted(stdout(), title, ["adapter", "complete", *names, "left out"], rows)


def _pct(value: float) -> str:
    return "–" if math.isnan(float(value)) else f"{100 * value:.1f}%"
