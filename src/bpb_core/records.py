"""Typed registration records that plugin hooks yield.

A record names a component and says how to build it; ``load`` is called only when the component
is used, so a plugin can register a component backed by a heavy library (litellm, pymunk) at no
import cost.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

Kind = Literal["task", "scene_family", "simulator", "adapter", "scorer"]
KINDS: tuple[Kind, ...] = ("task", "scene_family", "simulator", "adapter", "scorer")


def lazy(reference: str) -> Callable[[], Any]:
    """Return a loader for ``"package.module:attribute"`` that imports only when called."""
    module_name, _, attribute = reference.partition(":")
    if not module_name or not attribute:
        raise ValueError(f"lazy reference must look like 'module:attribute', got {reference!r}")

    def load() -> Any:
        return getattr(importlib.import_module(module_name), attribute)

    load.__qualname__ = f"lazy({reference!r})"
    return load


@dataclass(frozen=True)
class ComponentInfo:
    """Common fields of every registration record.

    Attributes:
        name: The name users type (``q1``, ``analytic``, ``litellm``).
        load: Zero-argument callable returning the component class or factory.
        summary: One line for ``bpb plugins`` and ``bpb list``.
    """

    name: str
    load: Callable[[], Any] = field(repr=False, compare=False)
    summary: str = ""

    kind: Kind = field(init=False, default="task")


@dataclass(frozen=True)
class TaskInfo(ComponentInfo):
    """A question asked about a scene (``q1``). ``load()`` returns a :class:`Task` class."""

    kind: Kind = field(init=False, default="task")


@dataclass(frozen=True)
class SceneFamilyInfo(ComponentInfo):
    """A generator of a kind of scene. ``load()`` returns a :class:`SceneFamily` class."""

    kind: Kind = field(init=False, default="scene_family")


@dataclass(frozen=True)
class SimulatorInfo(ComponentInfo):
    """A physics engine. ``load()`` returns a :class:`Simulator` class (no-argument constructor
    or keyword options such as ``dt``)."""

    kind: Kind = field(init=False, default="simulator")


@dataclass(frozen=True)
class AdapterInfo(ComponentInfo):
    """A model provider. Specs are ``name:model``; ``load()`` returns a factory called as
    ``factory(model, options)`` that builds a :class:`ModelAdapter`.

    Attributes:
        models: Models worth listing (``stasis``, ``oracle``); empty when any string goes.
    """

    models: tuple[str, ...] = ()
    kind: Kind = field(init=False, default="adapter")


@dataclass(frozen=True)
class ScorerInfo(ComponentInfo):
    """Scores one task's answers. ``load()`` returns a :class:`Scorer` class.

    Attributes:
        task: Name of the task whose answers it scores.
    """

    task: str = ""
    kind: Kind = field(init=False, default="scorer")


@dataclass(frozen=True)
class Registered:
    """A record together with the plugin and distribution that supplied it."""

    info: ComponentInfo
    plugin: str
    distribution: str
    version: str
