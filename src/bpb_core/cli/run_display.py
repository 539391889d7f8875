"""The live display of ``bpb run``: one progress row per (adapter, task)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rich.markup import escape

from bpb_core.runner.options import ProgressEvent

if TYPE_CHECKING:
    from rich.progress import Progress as RichBar, TaskID


@dataclass
class _Row:
    task_id: TaskID
    total: int = 0
    done_before: int = 0
    ok: int = 0
    parse_error: int = 0
    api_error: int = 0
    not_sent: int = 0
    retries: int = 0
    tokens: int = 0
    cost: float | None = 0.0

    def fields(self) -> dict[str, Any]:
        cost = "$?" if self.cost is None else f"${self.cost:.4f}"
        failed = self.parse_error + self.api_error
        text = (
            f"ok {self.ok} failed {failed} (parse {self.parse_error}, api {self.api_error}) "
            f"retrying {self.retries} tok {self.tokens:,} {cost}"
        )
        if self.done_before:
            text += f" | {self.done_before} done before"
        if self.not_sent:
            text += f" | {self.not_sent} not sent"
        return {"stats": text}


class RichProgress:
    """Draws :class:`~bpb_core.runner.options.ProgressEvent` s as rich progress bars."""

    def __init__(self, bar: RichBar) -> None:
        self._bar = bar
        self._rows: dict[tuple[str, str], _Row] = {}

    def _row(self, event: ProgressEvent) -> _Row:
        key = (event.adapter, event.task)
        if key not in self._rows:
            name = escape(f"{event.adapter} {event.task}")
            task_id = self._bar.add_task(name, total=0, stats="")
            self._rows[key] = _Row(task_id)
        return self._rows[key]

    def update(self, event: ProgressEvent) -> None:
        """Apply one event to its row (a warning is printed above the bars)."""
        if event.kind == "warning":
            text = escape(f"{event.adapter}: {event.reason}")
            self._bar.console.print(f"[yellow]warning:[/] {text}")
            return
        row = self._row(event)
        if event.kind == "planned":
            row.total += event.count
        elif event.kind == "skipped":
            row.done_before += event.count
        elif event.kind == "retry":
            row.retries += 1
        elif event.kind == "done":
            status = event.status or "ok"
            setattr(row, status, getattr(row, status, 0) + 1)
            row.tokens += event.tokens
            if row.cost is not None:
                row.cost = None if event.cost is None else row.cost + event.cost
        finished = row.ok + row.parse_error + row.api_error + row.not_sent
        self._bar.update(row.task_id, total=row.total, completed=finished, **row.fields())


def make_bar() -> RichBar:
    """A rich progress bar on stderr with the run's columns."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

    from bpb_core.cli.console import stderr

    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[stats]}"),
        console=stderr(),
        transient=False,
    )
