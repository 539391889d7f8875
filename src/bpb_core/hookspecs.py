"""The hooks a bpb plugin can implement.

A plugin is a module (or object) exposed under the ``bpb`` entry-point group. Each hook takes no
arguments and returns an iterable of registration records (see :mod:`bpb_core.registry`).
Names must be unique per kind across all installed plugins; a clash is an error naming both
distributions.

Example ``pyproject.toml`` of a third-party adapter::

    [project.entry-points.bpb]
    echo = "bpb_echo.hooks"

and ``bpb_echo/hooks.py``::

    from bpb_core import AdapterInfo, hookimpl, lazy

    @hookimpl
    def bpb_model_adapters():
        yield AdapterInfo("echo", lazy("bpb_echo.adapter:make_adapter"), "Echoes a fixed answer")
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

import pluggy

if TYPE_CHECKING:  # the registry imports this module
    from bpb_core.registry import (
        AdapterInfo,
        DiagnosticInfo,
        Kind,
        ReferenceInfo,
        SceneFamilyInfo,
        ScorerInfo,
        SimulatorInfo,
        SuiteInfo,
        TaskInfo,
    )

PROJECT = "bpb"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


@hookspec
def bpb_eval_tasks() -> Iterable[TaskInfo]:  # type: ignore[empty-body]
    """Register tasks: questions asked about the scenes of one family, each with its prompt,
    answer schema, parser and expected answer.

    Returns:
        :class:`~bpb_core.registry.TaskInfo` records (``family`` names the scene family,
        ``default`` puts the task in ``bpb run``'s default set); ``load()`` gives a class
        implementing :class:`~bpb_core.interfaces.Task`.
    """


@hookspec
def bpb_scene_families() -> Iterable[SceneFamilyInfo]:  # type: ignore[empty-body]
    """Register scene families: kinds of scene with their files, sampler, ground truth and
    pictures.

    Returns:
        :class:`~bpb_core.registry.SceneFamilyInfo` records (``default``: the family
        ``bpb generate`` uses without ``--family``); ``load()`` gives a class implementing
        :class:`~bpb_core.interfaces.SceneFamily`.
    """


@hookspec
def bpb_simulators() -> Iterable[SimulatorInfo]:  # type: ignore[empty-body]
    """Register physics simulators that turn a scene of one family into its outcome at a
    horizon.

    Returns:
        :class:`~bpb_core.registry.SimulatorInfo` records (``family`` names the scene
        family); ``load()`` gives a class implementing :class:`~bpb_core.interfaces.Simulator`.
    """


@hookspec
def bpb_model_adapters() -> Iterable[AdapterInfo]:  # type: ignore[empty-body]
    """Register model adapters, addressed as ``name:model`` (split at the first colon).

    Returns:
        :class:`~bpb_core.registry.AdapterInfo` records (``offline``: runs with no network
        or key, so ``bpb run`` uses its ``models`` by default); ``load()`` gives a factory
        ``factory(model: str, options: AdapterOptions) -> ModelAdapter``.
    """


@hookspec
def bpb_scorers() -> Iterable[ScorerInfo]:  # type: ignore[empty-body]
    """Register scorers, each bound to one task by name.

    Returns:
        :class:`~bpb_core.registry.ScorerInfo` records; ``load()`` gives a class
        implementing :class:`~bpb_core.interfaces.Scorer` (and optionally
        :class:`~bpb_core.capabilities.ExplainsErrors` and
        :class:`~bpb_core.capabilities.DrawsOverlay` for the failure gallery).
    """


@hookspec
def bpb_suites() -> Iterable[SuiteInfo]:  # type: ignore[empty-body]
    """Register suites: weighted totals over tasks (a paper's headline score).

    Reports show every suite all of whose tasks ran, beside the task scores.

    Returns:
        :class:`~bpb_core.registry.SuiteInfo` records (``weights``: task to weight).
    """


@hookspec
def bpb_references() -> Iterable[ReferenceInfo]:  # type: ignore[empty-body]
    """Register published figures (a paper's stated scores per model and task).

    ``bpb report`` shows each figure beside a run of the same model, with the run's score,
    its interval and the difference.

    Returns:
        :class:`~bpb_core.registry.ReferenceInfo` records.
    """


@hookspec
def bpb_diagnostics() -> Iterable[DiagnosticInfo]:  # type: ignore[empty-body]
    """Register diagnostics: tables (and charts) derived from scored results.

    Returns:
        :class:`~bpb_core.registry.DiagnosticInfo` records (``tasks``: shown when any of
        them ran); ``load()`` gives a class implementing
        :class:`~bpb_core.interfaces.Diagnostic`.
    """


HOOK_KINDS: dict[str, Kind] = {
    "bpb_eval_tasks": "task",
    "bpb_scene_families": "scene_family",
    "bpb_simulators": "simulator",
    "bpb_model_adapters": "adapter",
    "bpb_scorers": "scorer",
    "bpb_suites": "suite",
    "bpb_diagnostics": "diagnostic",
    "bpb_references": "reference",
}
