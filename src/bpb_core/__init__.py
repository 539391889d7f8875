"""bpb core: the plugin system, interfaces and data models of BilliardPhys-Bench.

Names are imported lazily on first use so that ``import bpb_core`` (and ``bpb --help``) stays
cheap; nothing here imports litellm, pandas, matplotlib or pymunk.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_EXPORTS: dict[str, str] = {
    # plugin system
    "hookimpl": "bpb_core.hookspecs",
    "hookspec": "bpb_core.hookspecs",
    "make_registry": "bpb_core.registry",
    "Registry": "bpb_core.registry",
    "PluginWarning": "bpb_core.registry",
    "lazy": "bpb_core.records",
    "TaskInfo": "bpb_core.records",
    "SceneFamilyInfo": "bpb_core.records",
    "SimulatorInfo": "bpb_core.records",
    "AdapterInfo": "bpb_core.records",
    "ScorerInfo": "bpb_core.records",
    # interfaces
    "Task": "bpb_core.interfaces",
    "SceneFamily": "bpb_core.interfaces",
    "Simulator": "bpb_core.interfaces",
    "ModelAdapter": "bpb_core.interfaces",
    "Scorer": "bpb_core.interfaces",
    "PromptOptions": "bpb_core.interfaces",
    "ParsedAnswer": "bpb_core.interfaces",
    # values
    "Scene": "bpb_core.scene",
    "FinalState": "bpb_core.scene",
    "Outcome": "bpb_core.outcome",
    "final_state": "bpb_core.outcome",
    "simulate_paths": "bpb_core.simulate",
    "simulate_scene": "bpb_core.simulate",
    # results and reports (pandas is imported when these are used)
    "load_results": "bpb_core.results",
    "load_frame": "bpb_core.results",
    "build_report": "bpb_core.report.build",
    "generate_dataset": "bpb_core.dataset",
    "load_dataset": "bpb_core.dataset",
    "Dataset": "bpb_core.dataset",
    # running evaluations
    "run_eval": "bpb_core.runner",
    "evaluate": "bpb_core.runner",
    "RunOptions": "bpb_core.runner.types",
    "RetryPolicy": "bpb_core.runner.types",
    "RunResult": "bpb_core.runner.types",
    "ProgressEvent": "bpb_core.runner.types",
    "ModelRequest": "bpb_core.adapters",
    "ModelResponse": "bpb_core.adapters",
    "Message": "bpb_core.adapters",
    "TextPart": "bpb_core.adapters",
    "ImagePart": "bpb_core.adapters",
    "Usage": "bpb_core.adapters",
    "AdapterOptions": "bpb_core.adapters",
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
    from bpb_core.adapters import (
        AdapterOptions,
        ImagePart,
        Message,
        ModelRequest,
        ModelResponse,
        TextPart,
        Usage,
    )
    from bpb_core.dataset import Dataset, generate_dataset, load_dataset
    from bpb_core.errors import BadInput, BpbError, ParseFailure
    from bpb_core.hookspecs import hookimpl, hookspec
    from bpb_core.interfaces import (
        ModelAdapter,
        ParsedAnswer,
        PromptOptions,
        SceneFamily,
        Scorer,
        Simulator,
        Task,
    )
    from bpb_core.outcome import Outcome, final_state
    from bpb_core.records import (
        AdapterInfo,
        SceneFamilyInfo,
        ScorerInfo,
        SimulatorInfo,
        TaskInfo,
        lazy,
    )
    from bpb_core.registry import PluginWarning, Registry, make_registry
    from bpb_core.report.build import build_report
    from bpb_core.results import load_frame, load_results
    from bpb_core.runner import evaluate, run_eval
    from bpb_core.runner.types import ProgressEvent, RetryPolicy, RunOptions, RunResult
    from bpb_core.scene import FinalState, Scene
    from bpb_core.simulate import simulate_paths, simulate_scene
