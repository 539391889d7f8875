"""How a run's pairs are sent: in a seeded order, through a bounded window of tasks, stopped by
Ctrl-C or SIGTERM, and run to the end from synchronous code.

Order: every (scene, task) pair is shuffled with a seeded generator. Sent in dataset order, a
run stopped early (``--max-cost``, Ctrl-C, a quota) would hold the first horizons complete and
the last ones empty, and any per-horizon table would be made of missing answers. Shuffled, any
prefix of the run is a uniform sample of the pairs, so a partial run's accuracy by horizon, scene
or task estimates the full run's. The whole plan is shuffled before finished pairs are dropped,
so a resumed run goes on in the same order; the seed is kept in ``run.json``.

Signals: the first one stops new calls; the calls in flight (already paid for) finish and are
written, and ``run.json`` records ``stopped: "interrupted"``. A second signal abandons the calls
still in flight (their pairs stay unsent and are asked again on resume). Handlers are installed
only when the run owns its event loop in the main thread (``bpb run``, a synchronous
``run_eval``: see :func:`owning_signals`), and the process's handlers are put back as they were
when it ends. A run awaited in the caller's own loop (``run_eval_async`` in an async app or a
notebook) and a run in a worker thread leave the signals to the caller, whose way to stop it is
cancelling its task.
"""

from __future__ import annotations

import asyncio
import contextlib
import contextvars
import hashlib
import random
import signal
import threading
from collections.abc import Callable, Coroutine, Iterator, Sequence
from typing import Any, TypeVar

from bpb_core.runner.budget import pair_name
from bpb_core.runner.call import PairCall
from bpb_core.runner.options import ProgressEvent
from bpb_core.runner.scenes import SceneRef
from bpb_core.runner.state import RunState

INTERRUPTED = "interrupted"
_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_OWNS_SIGNALS = contextvars.ContextVar("bpb_owns_signals", default=False)
T = TypeVar("T")


Pair = tuple[SceneRef, str, int]
"""A scene, a task and the epoch (1 unless ``--epochs`` asks for repeated samples)."""


def call_order(
    refs: Sequence[SceneRef],
    tasks: Sequence[str],
    done: set[tuple[str, str, int]],
    seed: int,
    epochs: int = 1,
) -> list[Pair]:
    """The (scene, task, epoch) samples still to send, in the run's seeded random order.

    Args:
        refs: The scenes the run asks about.
        tasks: The tasks asked about each scene.
        done: ``(scene_id, task, epoch)`` samples already finished (dropped from the result).
        seed: The order seed (recorded in ``run.json``; a resume reuses it).
        epochs: Samples per (scene, task).

    Returns:
        A uniform random permutation of the samples not yet done.
    """
    pairs = [(ref, task, e) for e in range(1, epochs + 1) for ref in refs for task in tasks]
    random.Random(f"bpb-call-order:{seed}").shuffle(pairs)
    return [(r, t, e) for r, t, e in pairs if (r.scene_id, t, e) not in done]


async def owning_signals(run: Coroutine[Any, Any, T]) -> T:
    """Await ``run`` as the owner of its event loop: its runs handle SIGINT and SIGTERM (for
    the coroutine given to ``asyncio.run`` by a synchronous entry point, never a caller's)."""
    _OWNS_SIGNALS.set(True)  # in this task's own context: the caller's stays as it was
    return await run


def _on_signal(state: RunState, jobs: set[asyncio.Task[None]]) -> None:
    state.interrupts += 1
    if state.interrupts == 1:
        state.stop(INTERRUPTED)  # also wakes the calls queued for a rate-limit slot
        state.progress.update(
            ProgressEvent(
                state.spec,
                "",
                "warning",
                reason="interrupted: no new calls; finishing the calls in flight "
                "(interrupt again to abandon them)",
            )
        )
        return
    for job in list(jobs):
        job.cancel()


@contextlib.contextmanager
def interruptible(state: RunState, jobs: set[asyncio.Task[None]]) -> Iterator[None]:
    """Handle SIGINT and SIGTERM on the running loop for the block, when the run owns the loop
    (:func:`owning_signals`) and it runs in the main thread; then restore the process's own
    handlers."""
    if not _OWNS_SIGNALS.get():
        yield
        return
    loop = asyncio.get_running_loop()
    installed: dict[signal.Signals, Any] = {}
    for sig in _SIGNALS:
        before = signal.getsignal(sig)
        try:
            loop.add_signal_handler(sig, _on_signal, state, jobs)
        except (RuntimeError, NotImplementedError):  # not the main thread; no signals here
            continue
        installed[sig] = before
    try:
        yield
    finally:
        for sig, before in installed.items():
            loop.remove_signal_handler(sig)
            if before is not None:  # None: a handler not set from Python, nothing to restore
                signal.signal(sig, before)


async def _pair(state: RunState, ref: SceneRef, task: str, epoch: int) -> None:
    if not state.may_send():
        state.not_sent(task, pair_name(ref.scene_id, task, epoch))
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
    :func:`interruptible`); a pair abandoned by a second signal stays unsent.
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


def run_sync(make: Callable[[], Coroutine[Any, Any, T]]) -> T:
    """Run the coroutine ``make()`` to its end and return its result.

    With no event loop running in this thread it gets one of its own (``asyncio.run``) and owns
    its signals (:func:`owning_signals`). Inside a running loop it
    runs on a loop of its own in a helper thread while this thread waits (the caller's loop is
    blocked meanwhile, as by any synchronous call; await ``run_eval_async`` to keep it
    serving). A ``KeyboardInterrupt`` while waiting (a notebook's interrupt), or the calling
    task being cancelled (``asyncio.run``'s Ctrl-C), cancels the run and waits for it to end
    (the folder stays resumable); the interrupt is raised, the cancellation reaches the caller
    at its next ``await``.
    """
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return asyncio.run(owning_signals(make()))
    return _in_thread(make)


def _in_thread(make: Callable[[], Coroutine[Any, Any, T]]) -> T:
    box: dict[str, Any] = {}
    started = threading.Event()

    async def main() -> T:
        box["loop"], box["task"] = asyncio.get_running_loop(), asyncio.current_task()
        started.set()
        return await make()

    def work() -> None:
        try:
            box["result"] = asyncio.run(main())
        except BaseException as exc:  # handed to the waiting thread
            box["error"] = exc
        finally:
            started.set()

    host = asyncio.current_task()  # cancelled by asyncio.run's Ctrl-C handler, for one
    cancelling = host.cancelling() if host is not None else 0
    thread = threading.Thread(target=work, name="bpb-run")
    thread.start()
    try:
        while thread.is_alive():
            thread.join(0.05)
            if host is not None and host.cancelling() > cancelling:
                _cancel(box, started)
                cancelling = host.cancelling()
    except KeyboardInterrupt:
        _cancel(box, started)
        thread.join()
        raise
    thread.join()
    if "error" in box:
        raise box["error"]
    result: T = box["result"]
    return result


def _cancel(box: dict[str, Any], started: threading.Event) -> None:
    """Cancel the run on the helper thread's loop (no-op once it has ended)."""
    started.wait()
    if "task" in box:
        with contextlib.suppress(RuntimeError):  # the loop has closed: the run has ended
            box["loop"].call_soon_threadsafe(box["task"].cancel)
