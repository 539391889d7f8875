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

_EXPORTS: dict[str, str] = {
    # plugin system
    "hookimpl": "bpb_core.hookspecs",
    "hookspec": "bpb_core.hookspecs",
    "make_registry": "bpb_core.registry",
    "Registry": "bpb_core.registry",
    "PluginWarning": "bpb_core.registry",
    "lazy": "bpb_core.registration",
    "TaskInfo": "bpb_core.registration",
    "SceneFamilyInfo": "bpb_core.registration",
    "SimulatorInfo": "bpb_core.registration",
    "AdapterInfo": "bpb_core.registration",
    "ScorerInfo": "bpb_core.registration",
    "SuiteInfo": "bpb_core.registration",
    "DiagnosticInfo": "bpb_core.registration",
    # interfaces and the values passed between them
    "Task": "bpb_core.interfaces",
    "Scene": "bpb_core.interfaces",
    "GroundTruth": "bpb_core.interfaces",
    "GeneratedScene": "bpb_core.interfaces",
    "SceneFamily": "bpb_core.interfaces",
    "Simulator": "bpb_core.interfaces",
    "ModelAdapter": "bpb_core.interfaces",
    "Scorer": "bpb_core.interfaces",
    "Diagnostic": "bpb_core.interfaces",
    "PromptOptions": "bpb_core.interfaces",
    "ParsedAnswer": "bpb_core.interfaces",
    "UnitRow": "bpb_core.scored_units",
    "ScenePicture": "bpb_core.picture",
    "extract": "bpb_core.reply_json",
    # the library face (pandas is imported when the results functions are used)
    "generate_dataset": "bpb_core.library",
    "load_dataset": "bpb_core.library",
    "export_hf": "bpb_core.library",
    "HfExport": "bpb_core.library",
    "Dataset": "bpb_core.library",
    "DatasetScene": "bpb_core.library",
    "build_messages": "bpb_core.library",
    "score_answer": "bpb_core.library",
    "answer_schema": "bpb_core.library",
    "AnswerScore": "bpb_core.library",
    "UnitScore": "bpb_core.library",
    "EvalResult": "bpb_core.library",
    "simulate_paths": "bpb_core.library",
    "run_eval": "bpb_core.library",
    "run_eval_async": "bpb_core.library",
    "evaluate": "bpb_core.library",
    "evaluate_async": "bpb_core.library",
    "load_results": "bpb_core.library",
    "load_frame": "bpb_core.library",
    "Results": "bpb_core.library",
    "leaderboard": "bpb_core.library",
    "build_report": "bpb_core.library",
    # running evaluations
    "RunOptions": "bpb_core.runner.options",
    "RetryPolicy": "bpb_core.runner.options",
    "RunResult": "bpb_core.runner.options",
    "ProgressEvent": "bpb_core.runner.options",
    "ModelRequest": "bpb_core.model_calls",
    "ModelResponse": "bpb_core.model_calls",
    "Message": "bpb_core.model_calls",
    "TextPart": "bpb_core.model_calls",
    "ImagePart": "bpb_core.model_calls",
    "Usage": "bpb_core.model_calls",
    "AdapterOptions": "bpb_core.model_calls",
    # errors
    "BpbError": "bpb_core.errors",
    "BadInput": "bpb_core.errors",
    "ParseFailure": "bpb_core.errors",
}

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
    from bpb_core.hookspecs import (
        hookimpl as hookimpl,
        hookspec as hookspec,
    )
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
    from bpb_core.picture import (
        ScenePicture as ScenePicture,
    )
    from bpb_core.registration import (
        AdapterInfo as AdapterInfo,
        DiagnosticInfo as DiagnosticInfo,
        SceneFamilyInfo as SceneFamilyInfo,
        ScorerInfo as ScorerInfo,
        SimulatorInfo as SimulatorInfo,
        SuiteInfo as SuiteInfo,
        TaskInfo as TaskInfo,
        lazy as lazy,
    )
    from bpb_core.registry import (
        PluginWarning as PluginWarning,
        Registry as Registry,
        make_registry as make_registry,
    )
    from bpb_core.reply_json import (
        extract as extract,
    )
    from bpb_core.runner.options import (
        ProgressEvent as ProgressEvent,
        RetryPolicy as RetryPolicy,
        RunOptions as RunOptions,
        RunResult as RunResult,
    )
    from bpb_core.scored_units import (
        UnitRow as UnitRow,
    )
