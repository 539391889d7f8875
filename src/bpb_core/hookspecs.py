"""The hooks a bpb plugin can implement.

A plugin is a module (or object) exposed under the ``bpb`` entry-point group. Each hook takes no
arguments and returns an iterable of registration records (see :mod:`bpb_core.records`). Names must
be unique per kind across all installed plugins; a clash is an error naming both distributions.

Example ``pyproject.toml`` of a third-party adapter::

    [project.entry-points.bpb]
    echo = "bpb_echo.hooks"

and ``bpb_echo/hooks.py``::

    from bpb_core import AdapterInfo, hookimpl, lazy

    @hookimpl
    def bpb_adapters():
        yield AdapterInfo("echo", lazy("bpb_echo.adapter:make_adapter"), "Echoes a fixed answer")
"""

from __future__ import annotations

from collections.abc import Iterable

import pluggy

from bpb_core.records import (
    AdapterInfo,
    Kind,
    SceneFamilyInfo,
    ScorerInfo,
    SimulatorInfo,
    TaskInfo,
)

PROJECT = "bpb"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


@hookspec
def bpb_tasks() -> Iterable[TaskInfo]:  # type: ignore[empty-body]
    """Register tasks: questions asked about a scene, each with prompt, answer schema and parser.

    Returns:
        :class:`~bpb_core.records.TaskInfo` records; ``load()`` gives a class implementing
        :class:`~bpb_core.interfaces.Task`.
    """


@hookspec
def bpb_scene_families() -> Iterable[SceneFamilyInfo]:  # type: ignore[empty-body]
    """Register scene families: generators of one kind of scene (the built-in is ``billiards``).

    Returns:
        :class:`~bpb_core.records.SceneFamilyInfo` records; ``load()`` gives a class implementing
        :class:`~bpb_core.interfaces.SceneFamily`.
    """


@hookspec
def bpb_simulators() -> Iterable[SimulatorInfo]:  # type: ignore[empty-body]
    """Register physics simulators that turn a scene into its state at a horizon.

    Returns:
        :class:`~bpb_core.records.SimulatorInfo` records; ``load()`` gives a class implementing
        :class:`~bpb_core.interfaces.Simulator`.
    """


@hookspec
def bpb_adapters() -> Iterable[AdapterInfo]:  # type: ignore[empty-body]
    """Register model adapters, addressed as ``name:model`` (split at the first colon).

    Returns:
        :class:`~bpb_core.records.AdapterInfo` records; ``load()`` gives a factory
        ``factory(model: str, options: AdapterOptions) -> ModelAdapter``.
    """


@hookspec
def bpb_scorers() -> Iterable[ScorerInfo]:  # type: ignore[empty-body]
    """Register scorers, each bound to one task by name.

    Returns:
        :class:`~bpb_core.records.ScorerInfo` records; ``load()`` gives a class implementing
        :class:`~bpb_core.interfaces.Scorer`.
    """


HOOK_KINDS: dict[str, Kind] = {
    "bpb_tasks": "task",
    "bpb_scene_families": "scene_family",
    "bpb_simulators": "simulator",
    "bpb_adapters": "adapter",
    "bpb_scorers": "scorer",
}
