"""The library face: what other programs call to generate, simulate, run and report.

Everything here is re-exported by :mod:`bpb_core` (lazily, so ``import bpb_core`` stays cheap);
the CLI is a thin wrapper over the same functions. Each one reaches scene families, tasks,
simulators, adapters, scorers, suites and diagnostics through a registry (``registry=``; default:
every installed plugin).

One question, one answer: the pieces another eval suite embeds. :func:`build_messages` gives the
exact messages ``bpb run`` would send, :func:`score_answer` parses a reply with the task's own
parser and marks it with the task's own scorer, returning plain Python values (no pandas needed
by the caller).

Whole evaluations: :func:`run_eval` and :func:`evaluate` wrap the runner
(:mod:`bpb_core.runner.run`, what ``bpb run`` calls): they take paths as ``str`` or
:class:`~pathlib.Path`, adapters as specs or objects, and return :class:`EvalResult`, the
runner's result with the scored frames of the run folder attached.
"""

from __future__ import annotations

import asyncio
import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.capabilities import PublishesSchema
from bpb_core.dataset.generate import generate_dataset
from bpb_core.dataset.reader import Dataset, DatasetScene, load_dataset, resolve_data
from bpb_core.errors import BadInput, ParseFailure
from bpb_core.interfaces import InputMode, PromptOptions
from bpb_core.library.hf_export import HfExport, export_hf
from bpb_core.plugin_calls import parsed_answer, prompt_messages, published_schema
from bpb_core.registry import make_registry
from bpb_core.report.build import Report, build_report
from bpb_core.results.frames import Results, load_frame, load_results
from bpb_core.results.tables import summary
from bpb_core.runner import run as runner
from bpb_core.runner.options import RunResult, check_input_mode
from bpb_core.scored_units import (
    check_scorer,
    input_frame,
    object_origin,
    scored_units,
    unit_rows,
)
from bpb_core.simulate import simulate_lines, simulate_paths

if TYPE_CHECKING:
    import pandas as pd

    from bpb_core.interfaces import ModelAdapter, Scorer, Task
    from bpb_core.model_calls import Message
    from bpb_core.registry import Registry
    from bpb_core.runner.options import RunOptions

__all__ = [
    "AnswerScore",
    "Dataset",
    "DatasetScene",
    "EvalResult",
    "HfExport",
    "Report",
    "Results",
    "UnitScore",
    "answer_schema",
    "build_messages",
    "build_report",
    "evaluate",
    "evaluate_async",
    "export_hf",
    "generate_dataset",
    "leaderboard",
    "load_dataset",
    "load_frame",
    "load_results",
    "run_eval",
    "run_eval_async",
    "score_answer",
    "simulate_lines",
    "simulate_paths",
    "summary",
]


@dataclass(frozen=True)
class UnitScore:
    """One scored unit of an answer (one labelled object, one item, one position).

    Attributes:
        unit: What the unit is (an id, a name).
        truth: The true label.
        pred: The predicted label (``None``: the answer does not mention it).
        correct: Whether the prediction is right.
        distance: Distance from the truth where the task measures one, else ``None``.
    """

    unit: str
    truth: str | None
    pred: str | None
    correct: bool
    distance: float | None


@dataclass(frozen=True)
class AnswerScore:
    """A reply, parsed and scored.

    Attributes:
        task: The task's name.
        scene_id: The scene asked about.
        status: ``ok`` (the reply holds a valid answer) or ``parse_error``.
        answer: The parsed answer in the task's answer format (``None`` on a parse error).
        rule: Which extraction rule found it (``None`` on a parse error).
        error: Why parsing failed (``None`` when it did not).
        units: Every scored unit, in the scorer's order.
        score: The scene's score under the task's rule (share of correct units, or 1.0 only
            when all are correct): what ``bpb report`` averages.
    """

    task: str
    scene_id: str
    status: str
    answer: dict[str, Any] | None
    rule: str | None
    error: str | None
    units: tuple[UnitScore, ...]
    score: float

    @property
    def correct(self) -> bool:
        """Whether every unit is right."""
        return all(unit.correct for unit in self.units)


def _task(task: str | Task, registry: Registry | None) -> tuple[Task, str]:
    """The task (a name looked up in ``registry``, default: every installed plugin) and who
    supplied it: its plugin when named, else the object's module."""
    if not isinstance(task, str):
        return task, object_origin(task)
    registry = registry or make_registry()
    return registry.task(task), registry.origin("task", task)


def prompt_options(task: Task, input_mode: InputMode, cot: bool | None) -> PromptOptions:
    """The options ``bpb run`` uses by default: the task's chain-of-thought default."""
    return PromptOptions(input_mode=input_mode, cot=task.default_cot if cot is None else cot)


def build_messages(
    task: str | Task,
    scene: DatasetScene,
    input_mode: InputMode = "image",
    *,
    cot: bool | None = None,
    registry: Registry | None = None,
) -> tuple[Message, ...]:
    """The messages ``bpb run`` sends for ``task`` about ``scene``: provider-neutral
    :class:`~bpb_core.model_calls.Message` values of text and image parts.

    Args:
        task: A task name (``--tasks`` takes the same) or a task object.
        scene: A scene of :func:`~bpb_core.dataset.reader.load_dataset`.
        input_mode: ``image`` (default), ``image+state`` or ``state`` (no image).
        cot: Ask for reasoning first; default: the task's own default.
        registry: Where a task name is looked up; default: every installed plugin.

    Raises:
        BadInput: The scene's files are missing or invalid (names the file), or the input
            mode is none of the three.
    """
    found, origin = _task(task, registry)
    check_input_mode(input_mode)
    image = None if input_mode == "state" else scene.image_bytes()
    options = prompt_options(found, input_mode, cot)
    return prompt_messages(found, origin, scene.state, image, options)


def score_answer(
    task: str | Task,
    scene: DatasetScene,
    reply_text: str,
    *,
    cot: bool | None = None,
    registry: Registry | None = None,
) -> AnswerScore:
    """Parse ``reply_text`` with the task's parser and score it against the scene's truth.

    A reply that holds no valid answer scores every unit wrong (``status="parse_error"``), as
    ``bpb run`` does after its re-asks.

    Args:
        task: A task name or a task object.
        scene: A scene of :func:`~bpb_core.dataset.reader.load_dataset`.
        reply_text: The model's whole reply.
        cot: Parse as a chain-of-thought reply (last valid JSON object); default: the task's.
        registry: Where the task and its scorer come from; default: every installed plugin.
    """
    registry = registry or make_registry()
    found, origin = _task(task, registry)
    options = prompt_options(found, "image", cot)
    try:
        parsed = parsed_answer(found, origin, reply_text, scene.state, options)
        status, answer, rule, error = "ok", parsed.value, parsed.rule, None
    except ParseFailure as exc:
        status, answer, rule, error = "parse_error", None, None, str(exc)
    scorer = registry.scorer_for(found.name)
    units = mark(scorer, answer, status, scene, origin=registry.scorer_entry(found.name).origin)
    right = [unit.correct for unit in units]  # the share right; 0.0 without units
    score = sum(right) / len(right) if right else 0.0
    if scorer.scene_rule == "all":  # all-or-nothing
        score = float(bool(right) and all(right))
    return AnswerScore(found.name, scene.scene_id, status, answer, rule, error, units, score)


def mark(
    scorer: Scorer,
    answer: dict[str, Any] | None,
    status: str,
    scene: DatasetScene,
    *,
    origin: str | None = None,
) -> tuple[UnitScore, ...]:
    """Cut ``answer`` into the scorer's units and score them (the scorer's vectorised rule).

    Args:
        origin: Who supplied the scorer, for the error below (``Registered.origin``; default:
            the scorer's module).

    Raises:
        PluginBug: The scorer's ``units`` or ``score`` raised or returned the wrong type, or
            its ``scene_rule`` or ``columns`` is unusable, in one line naming ``origin``, as
            ``load_results`` and ``bpb report`` say it.
    """
    who = origin if origin is not None else object_origin(scorer)
    check_scorer(scorer, who)
    rows = unit_rows(scorer, who, answer, scene.truth, scene.state)
    scored = scored_units(scorer, who, input_frame(scorer, [(status, rows)]))
    return tuple(
        UnitScore(row.unit, row.truth, row.pred, bool(ok), None if dist != dist else float(dist))
        for row, ok, dist in zip(rows, scored["correct"], scored["distance"], strict=True)
    )


def answer_schema(task: str | Task, *, registry: Registry | None = None) -> dict[str, Any]:
    """The JSON Schema of a task's answer (published in ``docs/schemas/`` for the built-ins).

    Raises:
        BadInput: The task publishes no schema.
        PluginBug: Its ``answer_schema()`` raised or returned no dict, naming the task's plugin.
    """
    found, origin = _task(task, registry)
    if not isinstance(found, PublishesSchema):
        raise BadInput(f"task {found.name!r}: publishes no answer schema")
    return published_schema(found, origin)


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
    failure does not stop the others; the options' ``max_cost`` caps them all together.
    """
    kwargs.setdefault("flag", "adapters")  # messages name the caller's parameter
    runs = [(Path(out) / runner.slug(_spec(adapter)), adapter) for adapter in _listed(adapters)]
    options = runner.sharing_cap(options, [d for d, _ in runs], kwargs)  # one cap for all
    return [run_eval(data, adapter, run_dir, options, **kwargs) for run_dir, adapter in runs]


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
