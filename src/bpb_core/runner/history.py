"""What earlier sessions of a run folder left in its attempts log, read in one pass.

The attempts log is the run's source of truth: every reply is appended (and flushed) before its
answer file is written. Reading it back gives three things a resumed run needs:

- the configuration hashes of earlier sessions, so a folder whose ``run.json`` is gone still
  cannot mix answers of another adapter, dataset, input mode or prompt setting;
- an ``ok`` reply whose answer file never got written (a kill between the two), which is
  recovered from the log instead of being paid for again;
- the attempts, tokens, cost and latency of every earlier session of a pair, so a pair retried
  in a later session counts all of them (usage tables and retries span sessions).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bpb_core.model_calls import known_cost
from bpb_core.run_folder import REPLIED, read_attempts, write_answer
from bpb_core.runner.scenes import SceneRef
from bpb_core.runner.state import RunState, Tally

_USAGE = ("input_tokens", "output_tokens", "reasoning_tokens", "cached_tokens")


@dataclass
class PairHistory:
    """The logged attempts of one (scene, task): their totals, and its last ``ok`` reply."""

    tally: Tally = field(default_factory=Tally)
    ok: dict[str, Any] | None = None

    def add(self, entry: dict[str, Any]) -> None:
        """Count one logged attempt."""
        tally = self.tally
        tally.attempts += 1
        if entry.get("outcome") not in REPLIED:
            return
        tally.responses += 1
        usage = entry.get("usage") or {}
        for name in _USAGE:
            value = usage.get(name) if isinstance(usage, dict) else None
            if isinstance(value, int):
                setattr(tally.usage, name, getattr(tally.usage, name) + value)
        cost = known_cost(entry.get("cost"))  # a NaN logged by an older bpb: unknown
        if tally.cost is not None:
            tally.cost = None if cost is None else tally.cost + cost
        latency = entry.get("latency")
        tally.latency += float(latency) if isinstance(latency, (int, float)) else 0.0
        if entry.get("outcome") == "ok" and isinstance(entry.get("answer"), dict):
            self.ok = entry


@dataclass
class History:
    """Configuration hashes seen and per-pair histories of one run folder."""

    configs: set[str] = field(default_factory=set)
    pairs: dict[tuple[str, str, int], PairHistory] = field(default_factory=dict)

    def prior(self, scene_id: str, task: str, epoch: int = 1) -> Tally:
        """A copy of the sample's totals so far (zero when it was never sent)."""
        found = self.pairs.get((scene_id, task, epoch))
        if found is None:
            return Tally()
        old = found.tally
        return Tally(old.attempts, old.responses, old.usage.model_copy(), old.cost, old.latency)


def read_history(run_dir: Path, adapter: str, keep: Iterable[tuple[str, str, int]] = ()) -> History:
    """Read the attempts log of ``run_dir`` once.

    Args:
        run_dir: The run folder.
        adapter: The run's name; attempts logged under another name are ignored for totals
            (their configuration hash still counts).
        keep: ``(scene_id, task, epoch)`` samples to collect totals for (others are only
            hashed).
    """
    wanted = set(keep)
    history = History()
    for entry in read_attempts(run_dir):
        config = entry.get("config")
        if isinstance(config, str):
            history.configs.add(config)
        epoch = entry.get("epoch", 1)
        pair = (str(entry.get("scene_id")), str(entry.get("task")), epoch)
        if pair in wanted and entry.get("adapter") == adapter:
            history.pairs.setdefault(pair, PairHistory()).add(entry)
    return history


def recover_answers(
    run_dir: Path,
    history: History,
    pending: Iterable[tuple[SceneRef, str, int]],
    state: RunState,
) -> set[tuple[str, str, int]]:
    """Write the answer file of every pending pair whose ``ok`` reply is already in the log.

    Args:
        run_dir: The run folder.
        history: Its attempts log, read by :func:`read_history`.
        pending: The pairs without a finished answer file.
        state: The run (its name, input mode and chain of thought per task, which the
            configuration hash guarantees the logged session shared).

    Returns:
        The ``(scene_id, task, epoch)`` samples recovered (never sent again).
    """
    recovered = set()
    for ref, task, epoch in pending:
        found = history.pairs.get((ref.scene_id, task, epoch))
        if found is None or found.ok is None:
            continue
        record = found.tally.record(
            ref,
            task,
            state.spec,
            status="ok",
            answer=found.ok["answer"],
            rule=found.ok.get("rule"),
            finish_reason=found.ok.get("finish_reason"),
            input_mode=state.options.input_mode,
            cot=state.cot(task),
            epoch=epoch,
        )
        write_answer(run_dir, ref.key, record)
        recovered.add((ref.scene_id, task, epoch))
    return recovered
