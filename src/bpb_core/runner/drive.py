"""Send a run's pairs in the plan's order through a bounded window of tasks."""

from __future__ import annotations

import asyncio
import hashlib

from bpb_core.runner.call import PairCall
from bpb_core.runner.interrupt import INTERRUPTED, interruptible
from bpb_core.runner.order import Pair
from bpb_core.runner.scenes import SceneRef
from bpb_core.runner.state import RunState


async def _pair(state: RunState, ref: SceneRef, task: str, epoch: int) -> None:
    if not state.may_send():
        state.not_sent(task)
        return
    scene = await state.offload(ref.load)
    image = None if state.options.input_mode == "state" else await state.offload(ref.image)
    sha = None if image is None else hashlib.sha256(image).hexdigest()
    tally = state.prior(ref.scene_id, task, epoch)
    await PairCall(state, ref, scene, image, sha, task, epoch, tally=tally).run()


async def _abandon(running: set[asyncio.Task[None]]) -> None:
    """Cancel the pairs in flight and wait until every one has ended (each counts itself as
    not sent), even if the caller cancels again meanwhile."""
    jobs = list(running)
    for job in jobs:
        job.cancel()
    while not all(job.done() for job in jobs):
        try:
            await asyncio.wait(jobs)
        except asyncio.CancelledError:
            continue


async def drive(state: RunState, plan: list[Pair]) -> None:
    """Run the pairs, in the plan's order, through a bounded window.

    The first scene error stops new pairs, lets the ones in flight finish (their answers are
    kept) and is raised. SIGINT/SIGTERM stop new pairs too (see
    :mod:`bpb_core.runner.interrupt`); a pair abandoned by a second signal stays unsent.
    Cancelling the run (``task.cancel()`` on a library caller's task) abandons the calls in
    flight the same way and waits for them to end, so none outlives the run (or its lock).
    """
    window = asyncio.Semaphore(max(2 * state.options.concurrency, 4))
    running: set[asyncio.Task[None]] = set()
    failures: list[BaseException] = []

    async def one(ref: SceneRef, task: str, epoch: int) -> None:
        try:
            await _pair(state, ref, task, epoch)
        except asyncio.CancelledError:  # abandoned by a second interrupt: resumable
            state.not_sent(task)
        except Exception as exc:  # re-raised below, after the scenes in flight finish
            failures.append(exc)
        finally:
            window.release()

    with interruptible(state, running):
        try:
            for ref, task, epoch in plan:
                await window.acquire()
                if failures:
                    window.release()
                    break
                job = asyncio.create_task(one(ref, task, epoch))
                running.add(job)
                job.add_done_callback(running.discard)
            if running:
                await asyncio.gather(*running, return_exceptions=True)
        except asyncio.CancelledError:
            state.stop(INTERRUPTED)
            await _abandon(running)
            raise
    if failures:
        raise failures[0]
