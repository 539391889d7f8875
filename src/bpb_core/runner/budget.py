"""Spending caps that hold: ``--max-cost`` over a whole command, per adapter, across sessions.

Before a call is sent, its worst case is reserved against every cap that covers it (the
command's, shared by all its adapters, and the adapter's own): the input tokens the adapter
counts, times a margin, at the input price, plus the call's output cap (``max_tokens``, else the
model's output limit) at the output price (:class:`~bpb_core.model_calls.CallCeiling`). A call
whose reservation does not fit waits while other calls are in flight, since each reply settles
its reservation at what it really cost and frees the rest; once nothing is in flight and it still
does not fit, the run stops sending (``stopped: "max-cost"``) and the pairs left are recorded as
kept from being sent by the cap.

A reply settles at its cost. A reply without a cost, and a call that timed out (the provider may
have billed it), settle at the reservation; a call that failed otherwise costs nothing. The input
margin starts at 25% and becomes 10% over the largest ratio of reported to counted input tokens
seen once that is larger, so a tokenizer that undercounts is corrected after its first reply.

Each reservation and settlement is appended to ``RUN_DIR/spending.jsonl`` (flushed): the
reservation before the call is sent, the settlement after it ends. A later session starts from
what earlier ones spent, and a reservation a killed session never settled counts in full.
"""

from __future__ import annotations

import asyncio
import time
import uuid
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bpb_core.errors import BadInput
from bpb_core.layout import SPENDING
from bpb_core.model_calls import CallCeiling, known_cost
from bpb_core.run_folder import AttemptLog, read_attempts

INPUT_MARGIN = 1.25
LEARNED_MARGIN = 1.1


@dataclass
class Budget:
    """One cap and what counts against it.

    Attributes:
        cap: USD (``None``: no cap; spending is still counted).
        spent: USD spent so far, earlier sessions included.
        reserved: USD held for calls in flight.
    """

    cap: float | None = None
    spent: float = 0.0
    reserved: float = 0.0

    def fits(self, amount: float) -> bool:
        """Whether ``amount`` more can be held without passing the cap."""
        return self.cap is None or self.spent + self.reserved + amount <= self.cap

    @property
    def left(self) -> float | None:
        """USD neither spent nor held (``None`` without a cap)."""
        return None if self.cap is None else max(0.0, self.cap - self.spent - self.reserved)

    @property
    def exhausted(self) -> bool:
        """Whether the cap is spent."""
        return self.cap is not None and self.spent >= self.cap


@dataclass(frozen=True)
class Hold:
    """One call's reservation."""

    key: str
    amount: float
    input_tokens: int


@dataclass
class Spending:
    """The caps over one run (one adapter in one event loop) and its reservations.

    Attributes:
        own: The run folder's budget (its cap: the adapter's ``max_cost``).
        shared: The command's budget, shared by all its adapters (``None`` for a lone run).
        scale: The input margin (see the module docstring).
        in_flight: Calls holding a reservation.
        kept: ``scene/task`` pairs the cap kept from being sent.
    """

    own: Budget = field(default_factory=Budget)
    shared: Budget | None = None
    scale: float = INPUT_MARGIN
    in_flight: int = 0
    kept: list[str] = field(default_factory=list)
    _room: asyncio.Event | None = None

    @property
    def budgets(self) -> tuple[Budget, ...]:
        """Every budget a call counts against."""
        return (self.own,) if self.shared is None else (self.own, self.shared)

    @property
    def capped(self) -> bool:
        """Whether any budget has a cap (calls are then reserved before they are sent)."""
        return any(b.cap is not None for b in self.budgets)

    @property
    def exhausted(self) -> bool:
        """Whether any cap is spent."""
        return any(b.exhausted for b in self.budgets)

    def amount(self, ceiling: CallCeiling, spec: str) -> float:
        """The reservation for a call bounded by ``ceiling``.

        Raises:
            BadInput: The adapter knows no output limit for the call (one line naming ``spec``).
        """
        if ceiling.output_cost is None:
            raise BadInput(unbounded(spec))
        return ceiling.input_cost * self.scale + ceiling.output_cost

    def hold(self, amount: float, input_tokens: int) -> Hold | None:
        """Reserve ``amount`` against every budget, or ``None`` if one has no room for it."""
        if not all(b.fits(amount) for b in self.budgets):
            return None
        for budget in self.budgets:
            budget.reserved += amount
        self.in_flight += 1
        return Hold(uuid.uuid4().hex[:16], amount, input_tokens)

    def room(self) -> asyncio.Event:
        """Set when the next reservation settles (then replaced by a fresh one)."""
        if self._room is None:
            self._room = asyncio.Event()
        return self._room

    def settle(self, hold: Hold | None, cost: float, input_tokens: int | None = None) -> None:
        """Count ``cost`` as spent and free ``hold`` (``None``: a call sent without one);
        ``input_tokens`` the reply reported, to correct the input margin."""
        for budget in self.budgets:
            budget.spent += cost
            if hold is not None:  # rounding must not leave a ghost of a reservation held
                left = budget.reserved - hold.amount
                budget.reserved = left if left > 1e-12 else 0.0
        if hold is None:
            return
        self.in_flight -= 1
        if input_tokens and hold.input_tokens:
            self.scale = max(self.scale, LEARNED_MARGIN * input_tokens / hold.input_tokens)
        if self._room is not None:
            self._room.set()
            self._room = None

    def summary(self) -> dict[str, Any]:
        """What ``run.json`` and the run's summary say: spent (all sessions), reserved (calls
        abandoned in flight: counted in full by the next session), left, the caps and the pairs
        the cap kept from being sent."""
        shared = self.shared or Budget()
        return {
            "cap": self.own.cap,
            "spent": self.own.spent,
            "reserved": self.own.reserved,
            "left": self.own.left,
            "command_cap": shared.cap,
            "command_spent": shared.spent if self.shared is not None else None,
            "command_left": shared.left,
            "kept_by_cap": list(self.kept),
        }


def pair_name(scene_id: str, task: str, epoch: int = 1) -> str:
    """``scene/task`` (``#eN`` after it for a later epoch), as the ledger and summaries name a
    pair."""
    return f"{scene_id}/{task}" + (f"#e{epoch}" if epoch > 1 else "")


def unbounded(spec: str) -> str:
    """The one-line error for a capped adapter that knows no output limit."""
    return (
        f"--max-cost: {spec}: no output limit known, so a call's worst case cannot be "
        "reserved; give --max-tokens (or max_tokens in its args)"
    )


def reservation_entry(hold: Hold, pair: str) -> dict[str, Any]:
    """The ledger line of a reservation."""
    return {"time": time.time(), "hold": hold.key, "usd": hold.amount, "pair": pair}


def settlement_entry(hold: Hold | None, cost: float, pair: str, basis: str) -> dict[str, Any]:
    """The ledger line of a settlement: ``basis`` ``reply`` (its cost), ``reservation`` (no
    cost known, or a timeout) or ``failed`` (nothing billed)."""
    key = None if hold is None else hold.key
    return {"time": time.time(), "settle": key, "usd": cost, "pair": pair, "basis": basis}


def past_spending(run_dir: Path) -> float:
    """USD the run folder's earlier sessions spent: its ledger's settlements plus every
    reservation never settled (a killed session's calls in flight); a folder without a ledger
    (an older bpb's) counts the costs in its attempts log."""
    if not (run_dir / SPENDING).exists():
        return sum(known_cost(e.get("cost")) or 0.0 for e in read_attempts(run_dir))
    held: dict[str, float] = {}
    spent = 0.0
    for entry in read_attempts(run_dir, SPENDING):
        usd = known_cost(entry.get("usd")) or 0.0
        if "hold" in entry:
            held[str(entry["hold"])] = usd
        elif "settle" in entry:
            spent += usd
            held.pop(str(entry["settle"]), None)
    return spent + sum(held.values())


def command_budget(cap: float | None, run_dirs: Sequence[Path]) -> Budget:
    """The budget one command's adapters share: ``cap`` and what their run folders' earlier
    sessions spent (read before the first adapter starts, so each counts the others')."""
    return Budget(cap, sum(past_spending(d) for d in run_dirs if d.is_dir()))


def open_ledger(run_dir: Path) -> tuple[AttemptLog, float]:
    """The run folder's ledger, opened for appending, and what earlier sessions spent. A new
    ledger in a folder an older bpb ran starts with what its attempts log says was spent."""
    new = not (run_dir / SPENDING).exists()
    before = past_spending(run_dir)
    ledger = AttemptLog(run_dir, SPENDING)
    if new and before:
        ledger.append(settlement_entry(None, before, "", "attempts"))
    return ledger, before
