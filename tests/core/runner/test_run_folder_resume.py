"""Resume safety in process: stale locks, the log's config guard, recovery, usage, Ctrl-C."""

from __future__ import annotations

import asyncio
import dataclasses
import json
import os
import signal
import time
from pathlib import Path

import pytest

from bpb_core.errors import BadInput, ServerError
from bpb_core.model_calls import ModelRequest, ModelResponse, Usage
from bpb_core.registry import Registry
from bpb_core.run_folder import iter_answers, read_attempts
from bpb_core.runner import RetryPolicy, RunOptions, run_eval


@dataclasses.dataclass
class Counting:
    """The oracle's answers with usage and a price; counts calls, fails or interrupts on cue."""

    oracle: object
    name: str = "fake:counting"
    calls: int = 0
    fail_first: int = 0
    interrupt_at: int = 0
    signals: int = 1
    cost: float | None = 0.5

    async def complete(self, request: ModelRequest) -> ModelResponse:
        self.calls += 1
        if self.calls == self.interrupt_at:
            for _ in range(self.signals):
                os.kill(os.getpid(), signal.SIGINT)
            await asyncio.sleep(0.2 * self.signals)  # a call still in flight
        if self.calls <= self.fail_first:
            raise ServerError("503 try later")
        right: ModelResponse = await self.oracle.complete(request)  # type: ignore[attr-defined]
        return dataclasses.replace(right, cost=self.cost, usage=Usage(100, 10), latency=0.25)


def _run(data: Path, run_dir: Path, registry: Registry, adapter: Counting, **kw: object) -> object:
    options = RunOptions(concurrency=1, retry=RetryPolicy(max_retries=0), **kw)  # type: ignore[arg-type]
    return run_eval(data, adapter, run_dir, options, registry=registry, spec=adapter.name)


def _records(run_dir: Path) -> dict[str, object]:
    return {f"{r.scene_id}/{r.task}": r for _, r in iter_answers(run_dir)}


def test_a_lock_left_by_a_dead_run_is_taken_over(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "run.lock").write_text("999999\\n")  # no such process holds it
    adapter = Counting(registry.adapter("baseline:oracle"))
    _run(dataset, tmp_path / "run", registry, adapter)
    assert adapter.calls == 18 and (tmp_path / "run" / "run.lock").read_text() == ""


def test_without_run_json_the_attempts_log_still_refuses_another_configuration(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    run_dir = tmp_path / "run"
    adapter = Counting(registry.adapter("baseline:oracle"))
    _run(dataset, run_dir, registry, adapter, input_mode="state", max_cost=1.4)
    (run_dir / "run.json").unlink()
    with pytest.raises(BadInput, match=r"attempts.jsonl: holds attempts of another config"):
        _run(dataset, run_dir, registry, adapter, input_mode="image")
    assert adapter.calls == 3
    _run(dataset, run_dir, registry, adapter, input_mode="state")  # the same settings resume
    assert adapter.calls == 18
    assert {r.input_mode for r in _records(run_dir).values()} == {"state"}


@pytest.mark.parametrize(
    "narrower",
    [{"limit": 1}, {"horizons": (1.0,)}, {"scenes": ("h1_0000",)}],
    ids=["limit", "horizons", "scenes"],
)
def test_resuming_with_a_narrower_selection_is_refused_and_keeps_every_answer(
    dataset: Path, tmp_path: Path, registry: Registry, narrower: dict[str, object]
) -> None:
    run_dir = tmp_path / "run"
    adapter = Counting(registry.adapter("baseline:oracle"))
    _run(dataset, run_dir, registry, adapter, limit=2)
    before = (run_dir / "run.json").read_bytes(), sorted(_records(run_dir))
    with pytest.raises(BadInput, match=r"holds answers outside this selection"):
        _run(dataset, run_dir, registry, adapter, **narrower)
    assert ((run_dir / "run.json").read_bytes(), sorted(_records(run_dir))) == before
    _run(dataset, run_dir, registry, adapter)  # a wider selection resumes, asking the rest
    assert adapter.calls == 18 and len(_records(run_dir)) == 18


def test_a_resume_may_add_tasks_but_keeps_each_held_task_s_chain_of_thought(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    # Chain of thought was compared as one setting over all tasks, so adding a task to a
    # folder was refused with a message about chain of thought the user had not changed.
    run_dir = tmp_path / "run"
    adapter = Counting(registry.adapter("baseline:oracle"))
    _run(dataset, run_dir, registry, adapter, tasks=("q1",), cot={"q1": False})
    assert adapter.calls == 6
    _run(dataset, run_dir, registry, adapter, tasks=("q1", "q2"), cot={"q1": False})
    assert adapter.calls == 12  # only q2 was asked
    assert json.loads((run_dir / "run.json").read_text())["tasks"] == ["q1", "q2"]
    before = (run_dir / "run.json").read_bytes(), sorted(_records(run_dir))
    with pytest.raises(BadInput, match=r"run.json: cot: this folder holds task q1 run with chain"):
        _run(dataset, run_dir, registry, adapter, tasks=("q1", "q2", "q3"), cot={"q1": True})
    with pytest.raises(BadInput, match=r"holds answers outside this selection \(h1_0000 q1"):
        _run(dataset, run_dir, registry, adapter, tasks=("q2",))
    assert ((run_dir / "run.json").read_bytes(), sorted(_records(run_dir))) == before
    assert adapter.calls == 12


def test_an_ok_reply_whose_answer_file_is_missing_is_recovered_not_resent(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    run_dir = tmp_path / "run"
    adapter = Counting(registry.adapter("baseline:oracle"))
    _run(dataset, run_dir, registry, adapter)
    before = _records(run_dir)
    for name in ("h1/scene_0000/q1.json", "h3/scene_0002/q3.json"):
        (run_dir / name).unlink()  # as if killed between the log line and the answer file
    _run(dataset, run_dir, registry, adapter)
    assert adapter.calls == 18
    assert _records(run_dir) == before


def test_a_cost_that_is_no_amount_is_recorded_as_unknown_never_summed(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    # Summed, a NaN cost made the run's spending NaN (so --max-cost never stopped it) and
    # went into the answer files and reports as NaN.
    run_dir = tmp_path / "run"
    adapter = Counting(registry.adapter("baseline:oracle"), cost=float("nan"))
    result = _run(dataset, run_dir, registry, adapter)
    assert result.cost is None and result.not_sent == 0  # type: ignore[attr-defined]
    assert {r.cost for r in _records(run_dir).values()} == {None}
    # An attempts log from before the fix holds NaN costs: a pair recovered from it (answer
    # file lost) is not paid for again and its cost is unknown, not NaN.
    log = run_dir / "attempts.jsonl"
    entries = [json.loads(line) for line in log.read_text().splitlines()]
    log.write_text("".join(json.dumps({**e, "cost": float("nan")}) + "\n" for e in entries))
    (run_dir / "h1/scene_0000/q1.json").unlink()
    _run(dataset, run_dir, registry, adapter)
    assert adapter.calls == 18 and _records(run_dir)["h1_0000/q1"].cost is None


def test_usage_and_retries_count_every_session(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    run_dir = tmp_path / "run"
    adapter = Counting(registry.adapter("baseline:oracle"), fail_first=18)
    _run(dataset, run_dir, registry, adapter)  # every pair fails once (no retries)
    _run(dataset, run_dir, registry, adapter)
    records = _records(run_dir).values()
    assert all(r.status == "ok" and r.attempts == 2 for r in records)
    assert {(r.usage.input_tokens, r.cost, r.latency) for r in records} == {(100, 0.5, 0.25)}
    adapter.fail_first = 40  # a third session over a folder with some pairs failing twice
    (run_dir / "h1/scene_0001/q2.json").unlink()  # recovered from the log with both attempts
    _run(dataset, run_dir, registry, adapter)
    assert _records(run_dir)["h1_0001/q2"].attempts == 2


def test_ctrl_c_stops_sending_finishes_writing_and_records_interrupted(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    run_dir = tmp_path / "run"
    # what the process had before (Python's default, or SIG_IGN when started in the background)
    before = signal.getsignal(signal.SIGINT)
    adapter = Counting(registry.adapter("baseline:oracle"), interrupt_at=4)
    result = _run(dataset, run_dir, registry, adapter)
    assert result.stopped == "interrupted" and adapter.calls == 4  # type: ignore[attr-defined]
    assert len(_records(run_dir)) == 4  # the call in flight at the signal was written
    assert json.loads((run_dir / "run.json").read_text())["stopped"] == "interrupted"
    assert signal.getsignal(signal.SIGINT) is before  # handler restored
    # A second signal abandons the call in flight: not written, not logged, sent on resume.
    twice = Counting(registry.adapter("baseline:oracle"), interrupt_at=5, signals=2)
    result = _run(dataset, run_dir, registry, twice)
    assert twice.calls == 5 and result.not_sent == 10  # type: ignore[attr-defined]
    assert len(_records(run_dir)) == 8
    logged = {f"{e['scene_id']}/{e['task']}" for e in read_attempts(run_dir)}
    assert logged == set(_records(run_dir))


def test_ctrl_c_during_a_backoff_stops_the_run_at_once(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    # the pair backing off after a 503 used to sleep its whole backoff (here 30 to 60 s)
    run_dir = tmp_path / "run"
    adapter = Counting(registry.adapter("baseline:oracle"), fail_first=1, interrupt_at=1)
    retry = RetryPolicy(max_retries=3, base_delay=60.0)
    options = RunOptions(concurrency=1, retry=retry)
    started = time.monotonic()
    result = run_eval(dataset, adapter, run_dir, options, registry=registry, spec=adapter.name)
    assert time.monotonic() - started < 10
    assert result.stopped == "interrupted" and adapter.calls == 1 and result.not_sent == 18
    assert _records(run_dir) == {}  # nothing answered, all resumable


def test_a_run_from_another_thread_leaves_signals_to_its_caller(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    # an eval suite calling the library from a worker thread: no signal handler can be
    # installed there, so the run goes on without one and the process keeps its own
    import threading

    before = signal.getsignal(signal.SIGINT)
    adapter = Counting(registry.adapter("baseline:oracle"))
    done: list[object] = []
    worker = threading.Thread(
        target=lambda: done.append(_run(dataset, tmp_path / "run", registry, adapter))
    )
    worker.start()
    worker.join(60)
    assert len(done) == 1 and done[0].stopped is None  # type: ignore[attr-defined]
    assert adapter.calls == 18 and len(_records(tmp_path / "run")) == 18
    assert signal.getsignal(signal.SIGINT) is before
