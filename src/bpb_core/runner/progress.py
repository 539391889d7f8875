"""Progress of an evaluation run: the events the runner reports and the protocol that takes them."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

EventKind = Literal["planned", "skipped", "retry", "done", "warning"]


@dataclass(frozen=True)
class ProgressEvent:
    """Something happened to one (scene, task) of one adapter.

    ``planned`` carries ``count`` calls to make; ``skipped`` ``count`` calls already complete
    from an earlier run; ``retry`` one failed attempt about to be repeated; ``done`` a final
    ``status`` with the tokens and cost of all its attempts; ``warning`` something the user
    should know about the whole run, in ``reason`` (sent once per adapter, e.g. a requested
    parameter the provider route dropped).
    """

    adapter: str
    task: str
    kind: EventKind
    count: int = 1
    status: str | None = None
    tokens: int = 0
    cost: float | None = None
    reason: str | None = None


class Progress(Protocol):
    """Receives progress events (the CLI draws them; the library never prints)."""

    def update(self, event: ProgressEvent) -> None:
        """Handle one event; must be quick (it runs on the event loop)."""
        ...


class NoProgress:
    """Ignores every event."""

    def update(self, event: ProgressEvent) -> None:
        return None
