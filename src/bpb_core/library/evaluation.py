"""Run evaluations from Python and get the scores back in the same call.

:func:`run_eval` and :func:`evaluate` wrap the runner (:mod:`bpb_core.runner.run`, what
``bpb run`` calls): they take paths as ``str`` or :class:`~pathlib.Path`, adapters as specs or
objects, and return :class:`EvalResult`, the runner's result with the scored frames of the run
folder attached.
"""

from __future__ import annotations

import asyncio
import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.dataset.hf_import import resolve_data
from bpb_core.results.frames import Results, load_results
from bpb_core.runner import run as runner
from bpb_core.runner.options import RunResult

if TYPE_CHECKING:
    import pandas as pd

    from bpb_core.interfaces import ModelAdapter
    from bpb_core.runner.options import RunOptions


@dataclass
class EvalResult(RunResult):
    """A :class:`~bpb_core.runner.options.RunResult` with the run folder's scored results.

    Attributes:
        results: Everything :func:`~bpb_core.results.frames.load_results` reads from the run
            folder (``units`` and ``calls`` frames, the suites that apply).
    """

    results: Results | None = None

    @property
    def scores(self) -> pd.DataFrame:
        """The scored units frame: one row per scored unit (see ``load_results``)."""
        assert self.results is not None  # always set by run_eval
        return self.results.units


def _spec(adapter: str | ModelAdapter) -> str:
    if isinstance(adapter, str):
        return adapter
    name = getattr(adapter, "name", None)
    return name if isinstance(name, str) and name else type(adapter).__name__


def run_eval(
    data: str | Path,
    adapter: str | ModelAdapter,
    run_dir: str | Path,
    options: RunOptions | None = None,
    **kwargs: Any,
) -> EvalResult:
    """Ask ``adapter`` every task about every selected scene of ``data``; write ``run_dir``;
    score it.

    Args:
        data: Dataset folder, or a Hugging Face export of one (``bpb export --format hf``).
        adapter: An adapter spec (``baseline:oracle``, ``litellm:gpt-5``) or an adapter object
            (anything with a ``name`` and an async ``complete(request)``).
        run_dir: The run folder (created; resumed when it holds an earlier run).
        options: Run options (tasks, horizons, limit, input mode, ...).
        **kwargs: ``registry``, ``adapter_options``, ``progress``, ``spec`` (the run's name
            when ``adapter`` is an object; default: its ``name``).

    Returns:
        Per-task status counts, cost and tokens, and ``scores``, the scored units frame.
    """
    done = runner.run_eval(resolve_data(data), adapter, Path(run_dir), options, **kwargs)
    return _scored(done, kwargs.get("registry"))


def _scored(done: RunResult, registry: Any) -> EvalResult:
    results = load_results(done.run_dir, registry=registry)
    return EvalResult(
        **{f.name: getattr(done, f.name) for f in dataclasses.fields(done)}, results=results
    )


async def run_eval_async(
    data: str | Path,
    adapter: str | ModelAdapter,
    run_dir: str | Path,
    options: RunOptions | None = None,
    **kwargs: Any,
) -> EvalResult:
    """:func:`run_eval` for callers inside an event loop (an async app): the calls run in the
    caller's loop, which keeps serving meanwhile; cancelling the task stops the run (the calls
    in flight are abandoned, the folder stays resumable). Arguments and result as
    :func:`run_eval`."""
    resolved = await asyncio.to_thread(resolve_data, data)
    done = await runner.run_eval_async(resolved, adapter, Path(run_dir), options, **kwargs)
    return await asyncio.to_thread(_scored, done, kwargs.get("registry"))


def evaluate(
    data: str | Path,
    adapters: Sequence[str | ModelAdapter] | str | ModelAdapter,
    out: str | Path,
    options: RunOptions | None = None,
    **kwargs: Any,
) -> list[EvalResult]:
    """Run several adapters one after the other, each into ``out/<slug(name)>/``.

    ``adapters`` is a list of specs or adapter objects; one spec or object alone is a list of
    one (a spec is never taken letter by letter). An adapter stopped by an authentication
    failure does not stop the others.
    """
    kwargs.setdefault("flag", "adapters")  # messages name the caller's parameter
    return [
        run_eval(data, adapter, Path(out) / runner.slug(_spec(adapter)), options, **kwargs)
        for adapter in _listed(adapters)
    ]


def _listed(adapters: Sequence[str | ModelAdapter] | str | ModelAdapter) -> list[Any]:
    if isinstance(adapters, str) or not isinstance(adapters, Sequence):
        return [adapters]
    return list(adapters)


async def evaluate_async(
    data: str | Path,
    adapters: Sequence[str | ModelAdapter] | str | ModelAdapter,
    out: str | Path,
    options: RunOptions | None = None,
    **kwargs: Any,
) -> list[EvalResult]:
    """:func:`evaluate` for callers inside an event loop (see :func:`run_eval_async`)."""
    kwargs.setdefault("flag", "adapters")
    return [
        await run_eval_async(data, one, Path(out) / runner.slug(_spec(one)), options, **kwargs)
        for one in _listed(adapters)
    ]


def leaderboard(
    results: Results | EvalResult | Sequence[EvalResult] | pd.DataFrame,
    suites: Sequence[Any] | None = None,
    **kwargs: Any,
) -> pd.DataFrame:
    """One row per run, best first: each task's score, each suite's total, completeness.

    Args:
        results: What :func:`run_eval`, :func:`evaluate` or
            :func:`~bpb_core.results.frames.load_results` returned, or a units frame.
        suites: Suites to total (default: those of ``results``, none for a bare frame).
        **kwargs: ``view`` (``strict`` or ``answered``), ``stable_only``, ``sort_by``.
    """
    from bpb_core.results import tables

    if isinstance(results, EvalResult):
        results = [results]
    if isinstance(results, Sequence):
        registry = kwargs.pop("registry", None)
        results = load_results([r.run_dir for r in results], registry=registry)
    if isinstance(results, Results):
        chosen = results.suites if suites is None else suites
        return tables.leaderboard(results.units, tuple(chosen), **kwargs)
    return tables.leaderboard(results, tuple(suites or ()), **kwargs)
