"""bpb core: the plugin system, the interfaces plugins implement, and the generic engine (dataset
writer, runner, results, reports) that reaches every scene family, task and adapter through
them.

Names are imported lazily on first use so that ``import bpb_core`` (and ``bpb --help``) stays
cheap; nothing here imports litellm, pandas, matplotlib or pymunk.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from bpb_core.version import __version__

# module -> the public names it defines (imported on first use)
_LAZY: dict[str, str] = {
    "bpb_core.hookspecs": "hookimpl hookspec",
    "bpb_core.registry": (
        "make_registry Registry PluginWarning lazy TaskInfo SceneFamilyInfo SimulatorInfo "
        "AdapterInfo ScorerInfo SuiteInfo DiagnosticInfo ReferenceInfo Figure"
    ),
    "bpb_core.interfaces": (
        "Task Scene GroundTruth GeneratedScene SceneFamily Simulator ModelAdapter Scorer "
        "Diagnostic PromptOptions ParsedAnswer"
    ),
    "bpb_core.scored_units": "UnitRow",
    "bpb_core.picture": "ScenePicture",
    "bpb_core.reply_json": "extract",
    "bpb_core.library": (
        "generate_dataset load_dataset export_hf HfExport Dataset DatasetScene "
        "build_messages score_answer answer_schema AnswerScore UnitScore EvalResult "
        "simulate_paths run_eval run_eval_async evaluate evaluate_async load_results "
        "load_frame Results leaderboard build_report"
    ),
    "bpb_core.runner.options": "RunOptions RetryPolicy RunResult ProgressEvent",
    "bpb_core.model_calls": (
        "ModelRequest ModelResponse Message TextPart ImagePart Usage AdapterOptions"
    ),
    "bpb_core.errors": "BpbError BadInput ParseFailure",
}
_EXPORTS = {name: module for module, names in _LAZY.items() for name in names.split()}

__all__ = ["__version__", *sorted(_EXPORTS)]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'bpb_core' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__


if TYPE_CHECKING:
    from bpb_core.errors import (
        BadInput as BadInput,
        BpbError as BpbError,
        ParseFailure as ParseFailure,
    )
    from bpb_core.hookspecs import hookimpl as hookimpl, hookspec as hookspec
    from bpb_core.interfaces import (
        Diagnostic as Diagnostic,
        GeneratedScene as GeneratedScene,
        GroundTruth as GroundTruth,
        ModelAdapter as ModelAdapter,
        ParsedAnswer as ParsedAnswer,
        PromptOptions as PromptOptions,
        Scene as Scene,
        SceneFamily as SceneFamily,
        Scorer as Scorer,
        Simulator as Simulator,
        Task as Task,
    )
    from bpb_core.library import (
        AnswerScore as AnswerScore,
        Dataset as Dataset,
        DatasetScene as DatasetScene,
        EvalResult as EvalResult,
        HfExport as HfExport,
        Results as Results,
        UnitScore as UnitScore,
        answer_schema as answer_schema,
        build_messages as build_messages,
        build_report as build_report,
        evaluate as evaluate,
        evaluate_async as evaluate_async,
        export_hf as export_hf,
        generate_dataset as generate_dataset,
        leaderboard as leaderboard,
        load_dataset as load_dataset,
        load_frame as load_frame,
        load_results as load_results,
        run_eval as run_eval,
        run_eval_async as run_eval_async,
        score_answer as score_answer,
        simulate_paths as simulate_paths,
    )
    from bpb_core.model_calls import (
        AdapterOptions as AdapterOptions,
        ImagePart as ImagePart,
        Message as Message,
        ModelRequest as ModelRequest,
        ModelResponse as ModelResponse,
        TextPart as TextPart,
        Usage as Usage,
    )
    from bpb_core.picture import ScenePicture as ScenePicture
    from bpb_core.registry import (
        AdapterInfo as AdapterInfo,
        DiagnosticInfo as DiagnosticInfo,
        Figure as Figure,
        PluginWarning as PluginWarning,
        ReferenceInfo as ReferenceInfo,
        Registry as Registry,
        SceneFamilyInfo as SceneFamilyInfo,
        ScorerInfo as ScorerInfo,
        SimulatorInfo as SimulatorInfo,
        SuiteInfo as SuiteInfo,
        TaskInfo as TaskInfo,
        lazy as lazy,
        make_registry as make_registry,
    )
    from bpb_core.reply_json import extract as extract
    from bpb_core.runner.options import (
        ProgressEvent as ProgressEvent,
        RetryPolicy as RetryPolicy,
        RunOptions as RunOptions,
        RunResult as RunResult,
    )
    from bpb_core.scored_units import UnitRow as UnitRow
