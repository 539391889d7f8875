"""Run-folder storage and pacing: atomic answers, torn log lines, the rpm and tpm caps."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path

from bpb_core.layout import SceneKey
from bpb_core.run_folder import (
    AnswerRecord,
    AttemptLog,
    completed,
    read_attempts,
    write_answer,
)
from bpb_core.runner.state import RateLimiter, TokenBudget


def test_torn_last_line_is_skipped_and_closed_before_appending(tmp_path: Path) -> None:
    log = AttemptLog(tmp_path)
    log.append({"n": 1})
    log.close()
    with (tmp_path / "attempts.jsonl").open("ab") as handle:
        handle.write(b'{"n": 2, "text": "cut o')  # what kill -9 can leave
    assert [e["n"] for e in read_attempts(tmp_path)] == [1]
    log = AttemptLog(tmp_path)
    log.append({"n": 3})
    log.close()
    assert [e["n"] for e in read_attempts(tmp_path)] == [1, 3]


def test_only_ok_and_parse_error_count_as_complete(tmp_path: Path) -> None:
    key = SceneKey(2.0, 5)
    for task, status in (("q1", "ok"), ("q2", "parse_error"), ("q3", "api_error")):
        record = AnswerRecord(
            scene_id=key.scene_id, horizon=2.0, index=5, task=task, adapter="x:y", status=status
        )  # type: ignore[arg-type]
        write_answer(tmp_path, key, record)
    (tmp_path / "h2/scene_0006").mkdir(parents=True)
    (tmp_path / "h2/scene_0006/q1.json").write_text('{"scene_id": "h2_00')  # corrupt: redo it
    assert completed(tmp_path) == {("h2_0005", "q1"), ("h2_0005", "q2")}
    assert not list((tmp_path / "h2/scene_0005").glob(".*tmp"))


def test_rpm_cap_spaces_request_starts() -> None:
    async def go() -> float:
        limiter = RateLimiter(rpm=600)  # one start per 0.1 s
        started = time.monotonic()
        await asyncio.gather(*(limiter.wait() for _ in range(5)))
        return time.monotonic() - started

    assert 0.35 < asyncio.run(go()) < 1.0
    assert asyncio.run(asyncio.wait_for(RateLimiter(None).wait(), 0.1)) is None


def test_tpm_cap_holds_calls_once_the_minute_budget_is_drawn() -> None:
    async def go() -> tuple[float, float]:
        budget = TokenBudget(tpm=12000)  # 200 tokens per second, a bucket of 12000
        await asyncio.wait_for(budget.wait(), 0.1)  # nothing known yet: no draw
        budget.spent(100)  # replies use 100 tokens on average: 120 calls fill the bucket
        started = time.monotonic()
        await asyncio.gather(*(budget.wait() for _ in range(120)))
        full = time.monotonic() - started
        await asyncio.gather(*(budget.wait() for _ in range(2)))  # 100 tokens leak in 0.5 s
        return full, time.monotonic() - started

    full, held = asyncio.run(go())
    assert full < 0.5 and 0.7 < held < 3.0


def test_rate_limit_waits_end_when_the_run_stops() -> None:
    # a call queued minutes ahead for its slot must not hold a stopped run open
    async def go() -> float:
        stop = asyncio.Event()
        limiter = RateLimiter(rpm=1)  # one start per minute
        budget = TokenBudget(tpm=100)
        budget.spent(100)
        await budget.wait(stop)  # the whole minute's budget drawn
        started = time.monotonic()
        waiting = asyncio.gather(*(limiter.wait(stop) for _ in range(3)), budget.wait(stop))
        await asyncio.sleep(0.2)
        stop.set()
        await asyncio.wait_for(waiting, 5)
        return time.monotonic() - started

    assert asyncio.run(go()) < 2.0
