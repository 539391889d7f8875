"""Evaluate model adapters on a dataset: the library behind ``bpb run``.

:func:`run_eval` runs one adapter into one run folder; :func:`evaluate` runs several, each into
``OUT/<slug>/``. Re-running the same call resumes: (scene, task) pairs whose answer file says
``ok`` or ``parse_error`` are never sent again; ``api_error`` ones are retried. The pairs are
sent in a seeded order, through a bounded window of tasks, stopped by Ctrl-C or SIGTERM, and run
to the end from synchronous code:

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
import dataclasses
import hashlib
import random
import re
import signal
import threading
from collections import Counter
from collections.abc import Callable, Coroutine, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from bpb_core.capabilities import NeedsSimulator
from bpb_core.dataset.manifest import check_simulator
from bpb_core.dataset.reader import DataFolder, open_folder
from bpb_core.errors import BadInput, WriteRefused
from bpb_core.layout import MANIFEST
from bpb_core.model_calls import AdapterOptions, adapter_problem, split_spec
from bpb_core.plugin_calls import answer_refusal, described_settings, preflight_problem
from bpb_core.run_folder import COMPLETE, AttemptLog, iter_answers, make_run_folder
from bpb_core.runner.budget import Budget, Spending, command_budget, open_ledger, pair_name
from bpb_core.runner.call import PairCall
from bpb_core.runner.manifest import finish_manifest, run_lock, start_manifest
from bpb_core.runner.options import NoProgress, Progress, ProgressEvent, RunOptions, RunResult
from bpb_core.runner.scenes import Asking, SceneRef, asking, check_images
from bpb_core.runner.state import (
    History,
    RateLimiter,
    RunState,
    TokenBudget,
    read_history,
    recover_answers,
)
from bpb_core.scored_units import object_origin

if TYPE_CHECKING:
    from bpb_core.interfaces import ModelAdapter
    from bpb_core.registry import Registry
    from bpb_core.run_folder import AnswerRecord


def slug(spec: str) -> str:
    """Folder name of an adapter spec: ``litellm:openai/gpt-5`` -> ``litellm_openai_gpt-5``;
    an option set in brackets joins it: ``litellm:gpt-5.4 [effort=high]`` ->
    ``litellm_gpt-5.4_effort=high``."""
    return re.sub(r"[^A-Za-z0-9._=,+-]+", "_", spec).strip("_")


def run_name(spec: str, adapter: ModelAdapter) -> str:
    """The name a run of ``adapter`` goes by: its own ``name`` when that extends ``spec`` with
    an option set (``litellm:gpt-5.4 [effort=high]``), else ``spec``."""
    name = getattr(adapter, "name", None)
    return name if isinstance(name, str) and name.startswith(spec) else spec


def check_adapter(spec: str, adapter: ModelAdapter, origin: str, flag: str = "--adapter") -> None:
    """Raise :class:`BadInput` when ``adapter`` cannot make a call (it has no async
    ``complete``: an object passed in by the caller, since the registry checks the ones its
    plugins build) or says before any call that no call can succeed. ``flag`` names where the
    adapter was given: ``--adapter``, or a library parameter (``adapter``, ``adapters``);
    ``origin`` who supplied it (:func:`adapter_origin`).

    Raises:
        BadInput: One line: what to fix (a missing key, an unknown provider, a module).
        PluginBug: Its ``preflight()`` raised or returned neither ``None`` nor a str.
    """
    shape = adapter_problem(adapter)
    if shape is not None:
        raise BadInput(
            f"adapter {spec}: {shape}; expected an object with an async complete(request)"
        )
    problem = preflight_problem(adapter, origin)
    if problem:
        raise BadInput(f"{flag} {spec}: {problem}")


def check_simulator_for(
    folder: DataFolder, spec: str, adapter: ModelAdapter, registry: Registry
) -> None:
    """Refuse ``adapter`` when it runs the dataset's simulator (:class:`NeedsSimulator`, e.g.
    ``baseline:oracle``) and ``folder``'s manifest names one that is not installed: its every
    call would fail. An adapter that does not run it (a model's, ``baseline:stasis``) runs on.

    Raises:
        BadInput: One line naming ``dataset.json``, the simulator and the installed ones.
    """
    if not (isinstance(adapter, NeedsSimulator) and adapter.needs_simulator()):
        return
    if folder.recorded is not None:  # without one, the family's default simulator (built in)
        made_with = folder.simulator_spec()
        check_simulator(folder.root / MANIFEST, made_with.name, registry, f"; {spec} runs it")


async def run_eval_async(
    data: Path | DataFolder,
    adapter: str | ModelAdapter,
    run_dir: Path,
    options: RunOptions | None = None,
    *,
    registry: Registry | None = None,
    adapter_options: AdapterOptions | None = None,
    progress: Progress | None = None,
    spec: str | None = None,
    flag: str = "adapter",
    shared_budget: Budget | None = None,
    pilot: int | None = None,
) -> RunResult:
    """Async form of :func:`run_eval` (for callers already inside an event loop). The set-up
    (the registry and the adapter built, the dataset and the run folder read) runs in a worker
    thread, so the caller's loop keeps serving its other tasks meanwhile. ``data``: the dataset
    folder, or a :class:`~bpb_core.dataset.reader.DataFolder` the caller has read."""
    progress = progress or NoProgress()
    setup = (data, adapter, run_dir, options, registry, adapter_options, spec, flag)
    asked, model, name, plugins, settings = await asyncio.to_thread(_prepare, *setup)
    with run_lock(run_dir):  # one session on the locked folder: guard, recover, send, record
        options, refs = asked.options, asked.scenes
        opened = await asyncio.to_thread(_opening, asked, name, run_dir, plugins, settings)
        history, held, manifest = opened
        ledger, spent_before = await asyncio.to_thread(open_ledger, run_dir)
        state = RunState(
            adapter=model,
            spec=name,
            tasks=asked.tasks,
            options=options,
            run_dir=run_dir,
            log=AttemptLog(run_dir),
            progress=progress,
            limiter=RateLimiter(options.rpm),
            budget=TokenBudget(options.tpm),
            slots=asyncio.Semaphore(options.concurrency),
            rng=random.Random(options.seed),
            family=asked.family.name,
            simulator=asked.simulator,
            config_hash=manifest["config_hash"],
            history=history,
            spending=Spending(Budget(options.max_cost, spent_before), shared_budget),
            ledger=ledger,
            origins={
                **{task: plugins.origin("task", task) for task in asked.tasks},
                name: adapter_origin(plugins, name, model),
            },
        )
        ended = False
        try:
            done = {(r.scene_id, r.task, r.epoch) for r in held if r.status in COMPLETE}
            plan = call_order(refs, options.tasks, done, manifest["order_seed"], options.epochs)
            done |= await asyncio.to_thread(recover_answers, run_dir, history, plan, state)
            plan = [(r, t, e) for r, t, e in plan if (r.scene_id, t, e) not in done]
            ids = {ref.scene_id for ref in refs}
            before = Counter(t for s, t, _ in done if s in ids)  # pairs done in earlier sessions
            if pilot is not None:  # a pilot tops the folder up to its share: none paid twice
                plan = pilot_pairs(plan, pilot, options.tasks, before)
            for task in options.tasks:
                todo = sum(1 for _, t, _ in plan if t == task)
                state.progress.update(ProgressEvent(name, task, "skipped", count=before[task]))
                state.progress.update(ProgressEvent(name, task, "planned", count=todo))
            await drive(state, plan)
            ended = True
        except WriteRefused as exc:
            state.stop("write-refused")  # run.json says why, when there is room for it
            raise WriteRefused(
                f"{exc}; the run stopped, and {run_dir} keeps every answer written so far: "
                "make room, then re-run the same command to resume"
            ) from None
        finally:
            state.io.shutdown(wait=True)
            with _kept_quiet(not ended):  # the disk that refused the run refuses these too
                state.log.close()
            with _kept_quiet(not ended):
                ledger.close()
            with _kept_quiet(not ended):
                finish_manifest(run_dir, manifest, state)
        return _result(state, before)


def _prepare(
    data: Path | DataFolder,
    adapter: str | ModelAdapter,
    run_dir: Path,
    options: RunOptions | None,
    registry: Registry | None,
    adapter_options: AdapterOptions | None,
    spec: str | None,
    flag: str,
) -> tuple[Asking, ModelAdapter, str, Registry, dict[str, Any] | None]:
    """What a run asks, its adapter (built and checked; errors name it after ``flag``), the
    run's name, the registry and the adapter's settings (checked); the run folder made."""
    from bpb_core.registry import make_registry

    registry = registry or make_registry()
    asked = asking(data, options or RunOptions(), registry)
    check_images(asked.folder, asked.scenes, asked.options.input_mode)
    made = adapter_options or AdapterOptions(seed=asked.options.seed)
    model = registry.adapter(adapter, made, flag=flag) if isinstance(adapter, str) else adapter
    if spec is None:
        spec = adapter if isinstance(adapter, str) else getattr(model, "name", type(model).__name__)
        spec = run_name(spec, model)
    origin = adapter_origin(registry, spec, model)
    check_adapter(spec, model, origin, flag)
    why = answer_refusal(model, origin, asked.family)
    if why is not None:
        raise BadInput(f"{flag} {spec}: {why}")
    check_simulator_for(asked.folder, spec, model, registry)
    settings = described_settings(model, origin)
    make_run_folder(run_dir)
    return asked, model, spec, registry, settings


def pilot_pairs(
    plan: list[Pair], count: int, tasks: Sequence[str], done: Counter[str]
) -> list[Pair]:
    """For ``--pilot``: the first pairs of ``plan`` (a seeded random order, so a uniform sample
    of the full run) that bring the pairs done to ``count``, spread evenly over the tasks
    (``done``: pairs already done per task, which count towards it)."""
    share = -(-count // max(len(tasks), 1))
    taken = Counter(done)
    left = count - sum(done[t] for t in tasks)
    chosen: list[Pair] = []
    for ref, task, epoch in plan:
        if len(chosen) < left and taken[task] < share:
            taken[task] += 1
            chosen.append((ref, task, epoch))
    return chosen


def _kept_quiet(failing: bool) -> contextlib.AbstractContextManager[None]:
    """While the run is failing, a write it refuses as well is left unsaid: the first error
    is the one to report."""
    return contextlib.suppress(WriteRefused) if failing else contextlib.nullcontext()


def _opening(
    asked: Asking,
    spec: str,
    run_dir: Path,
    registry: Registry,
    settings: dict[str, Any] | None,
) -> tuple[History, list[AnswerRecord], dict[str, Any]]:
    """The run folder read (its attempts log and answers) and ``run.json`` written."""
    options, refs = asked.options, asked.scenes
    epochs = range(1, options.epochs + 1)
    pairs = ((r.scene_id, t, e) for r in refs for t in options.tasks for e in epochs)
    history = read_history(run_dir, spec, pairs)
    ids = [ref.scene_id for ref in refs]
    held = [record for _, record in iter_answers(run_dir)]  # read once: guard and plan
    manifest = start_manifest(
        run_dir,
        spec,
        asked.folder,
        options,
        registry,
        len(refs),
        settings,
        history.configs,
        ids,
        held,
    )
    return history, held, manifest


def adapter_origin(registry: Registry, spec: str, model: object) -> str:
    """Who supplied the adapter run as ``spec``, for one-line plugin errors: the plugin that
    registers its name, else (an adapter object no plugin registers) its module (its name
    follows anyway)."""
    try:
        adapter = split_spec(spec)[0]
    except BadInput:  # an adapter object's own name ("buggy"), not a NAME:MODEL spec
        return object_origin(model)
    if adapter in registry.names("adapter"):
        return registry.origin("adapter", adapter)
    return object_origin(model)


def _result(state: RunState, before: Counter[str]) -> RunResult:
    statuses: dict[str, Counter[str]] = {}
    for task in state.options.tasks:
        counts = Counter(state.statuses.get(task, {}))
        counts["done_before"] = before[task]
        statuses[task] = counts
    return RunResult(
        run_dir=state.run_dir,
        adapter=state.spec,
        statuses=statuses,
        cost=None if state.unpriced else state.spent,
        tokens=state.tokens,
        stopped=state.stop_reason,
        error=None if state.setup_error is None else str(state.setup_error),
        budget=state.spending.summary(),
    )


def sharing_cap(
    options: RunOptions | None, run_dirs: Sequence[Path], kwargs: dict[str, Any]
) -> RunOptions:
    """The options each adapter of one command runs with: their ``max_cost`` becomes one
    budget all of them share (put in ``kwargs`` as ``shared_budget``), counting what their
    folders' earlier sessions spent."""
    options = options or RunOptions()
    if options.max_cost is None or "shared_budget" in kwargs:
        return options
    kwargs["shared_budget"] = command_budget(options.max_cost, run_dirs)
    return dataclasses.replace(options, max_cost=None)


def run_eval(
    data: Path | DataFolder,
    adapter: str | ModelAdapter,
    run_dir: Path,
    options: RunOptions | None = None,
    **kwargs: Any,
) -> RunResult:
    """Ask ``adapter`` every task about every selected scene of ``data``; write ``run_dir``.

    Args:
        data: Dataset folder (or a :class:`~bpb_core.dataset.reader.DataFolder` read once).
        adapter: An adapter spec (``baseline:oracle``, ``litellm:gpt-5``) or an adapter object.
        run_dir: The run folder (created; resumed when it holds an earlier run).
        options: Run options.
        **kwargs: ``registry``, ``adapter_options``, ``progress``, ``spec`` (the run's name
            when ``adapter`` is an object), ``flag`` (what messages call the adapter:
            ``adapter`` by default, ``--adapter`` from the command line), ``shared_budget``
            (a :class:`~bpb_core.runner.budget.Budget` capping several runs together),
            ``pilot`` (send only enough pairs to have N done, spread over the tasks).

    Returns:
        Per-task status counts, cost and tokens; ``stopped`` says why it stopped early.
        An error no retry can fix (an unknown model, a refused key, an unreachable provider)
        sets ``stopped="setup"`` and ``error``; the CLI turns it into exit code 2.
    """
    return run_sync(lambda: run_eval_async(data, adapter, run_dir, options, **kwargs))


def evaluate(
    data: Path | DataFolder,
    adapters: Sequence[str],
    out: Path,
    options: RunOptions | None = None,
    **kwargs: Any,
) -> list[RunResult]:
    """Run several adapters one after the other, each into ``out/<slug(spec)>/``.

    An adapter stopped by a setup failure (``stopped="setup"``) does not stop the others. The
    options' ``max_cost`` caps them all together, earlier sessions of their folders included.
    """
    kwargs.setdefault("flag", "adapters")
    data = open_folder(data, kwargs.get("registry"))
    options = sharing_cap(options, [out / slug(spec) for spec in adapters], kwargs)
    return [run_eval(data, spec, out / slug(spec), options, **kwargs) for spec in adapters]


INTERRUPTED = "interrupted"
WRITE_REFUSED = "write-refused"
FAILED = "failed"
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
        again = "interrupt again to abandon them"
        state.warn("", f"interrupted: no new calls; finishing the calls in flight ({again})")
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
    tally = state.history.prior(ref.scene_id, task, epoch)  # earlier sessions' attempts
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

    The first scene error (a refused write, a plugin's bug) stops every call not yet sent,
    queued ones included, lets the ones in flight finish (their answers are kept where the disk
    allows) and is raised. SIGINT/SIGTERM stop new pairs too (see
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
            # Now, not once the window is drained: the pairs queued for a slot would each be
            # paid for, and on a disk that refused one write their replies could not be kept.
            state.stop(WRITE_REFUSED if isinstance(exc, WriteRefused) else FAILED)
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
