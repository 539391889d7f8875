"""Typed registration records that plugin hooks yield.

A record names a component and says how to build it; ``load`` is called only when the component
is used, so a plugin can register a component backed by a heavy library (litellm, pymunk) at no
import cost. Fields beyond ``name``, ``load`` and ``summary`` are plain data that bpb reads
without loading the component (which family a task asks about, which task a scorer scores).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

Kind = Literal["task", "scene_family", "simulator", "adapter", "scorer", "suite", "diagnostic"]
KINDS: tuple[Kind, ...] = (
    "task",
    "scene_family",
    "simulator",
    "adapter",
    "scorer",
    "suite",
    "diagnostic",
)


def lazy(reference: str) -> Callable[[], Any]:
    """Return a loader for ``"package.module:attribute"`` that imports only when called."""
    module_name, _, attribute = reference.partition(":")
    if not module_name or not attribute:
        raise ValueError(f"lazy reference must look like 'module:attribute', got {reference!r}")

    def load() -> Any:
        return getattr(importlib.import_module(module_name), attribute)

    load.__qualname__ = f"lazy({reference!r})"
    return load


def _nothing_to_load() -> None:
    return None


@dataclass(frozen=True)
class ComponentInfo:
    """Common fields of every registration record.

    Attributes:
        name: The name users type (``analytic``, ``litellm``).
        load: Zero-argument callable returning the component class or factory.
        summary: One line for ``bpb plugins`` and ``bpb list``.
    """

    name: str
    load: Callable[[], Any] = field(default=_nothing_to_load, repr=False, compare=False)
    summary: str = ""

    kind: Kind = field(init=False, default="task")


@dataclass(frozen=True)
class TaskInfo(ComponentInfo):
    """A question asked about a scene. ``load()`` returns a :class:`~bpb_core.interfaces.Task`
    class.

    Attributes:
        family: The scene family whose scenes the task asks about.
        default: Asked by ``bpb run`` when ``--tasks`` is not given.
        title: Heading of the task's charts (default: its name).
    """

    family: str = ""
    default: bool = False
    title: str = ""
    kind: Kind = field(init=False, default="task")


@dataclass(frozen=True)
class SceneFamilyInfo(ComponentInfo):
    """A kind of scene. ``load()`` returns a :class:`~bpb_core.interfaces.SceneFamily` class.

    Attributes:
        default: The family ``bpb generate`` uses without ``--family`` (one family may say so).
    """

    default: bool = False
    kind: Kind = field(init=False, default="scene_family")


@dataclass(frozen=True)
class SimulatorInfo(ComponentInfo):
    """A physics engine for the scenes of one family. ``load()`` returns a
    :class:`~bpb_core.interfaces.Simulator` class (keyword options such as ``dt``).

    Attributes:
        family: The scene family whose scenes it simulates.
    """

    family: str = ""
    kind: Kind = field(init=False, default="simulator")


@dataclass(frozen=True)
class AdapterInfo(ComponentInfo):
    """A model provider. Specs are ``name:model``; ``load()`` returns a factory called as
    ``factory(model, options)`` that builds a :class:`~bpb_core.interfaces.ModelAdapter`.

    Attributes:
        models: Models worth listing (``stasis``, ``oracle``); empty when any string goes.
        offline: Needs no network and no key: ``bpb run`` without ``--adapter`` runs every
            listed model of every offline adapter.
        catalog: A loader (see :func:`lazy`) of a function returning ``(model, description)``
            rows for ``bpb list adapters`` (aliases of an adapter that takes any string).
    """

    models: tuple[str, ...] = ()
    offline: bool = False
    catalog: Callable[[], Any] | None = None
    kind: Kind = field(init=False, default="adapter")


@dataclass(frozen=True)
class ScorerInfo(ComponentInfo):
    """Scores one task's answers. ``load()`` returns a :class:`~bpb_core.interfaces.Scorer`
    class.

    Attributes:
        task: Name of the task whose answers it scores.
    """

    task: str = ""
    kind: Kind = field(init=False, default="scorer")


@dataclass(frozen=True)
class SuiteInfo(ComponentInfo):
    """A weighted total over tasks, shown beside the task scores wherever all its tasks ran.
    Nothing is loaded: the weights are the suite.

    Attributes:
        weights: Task name to weight; weights sum to 1.
        title: Heading of the suite's charts (default: its name).
    """

    weights: Mapping[str, float] = field(default_factory=dict)
    title: str = ""
    kind: Kind = field(init=False, default="suite")

    def __post_init__(self) -> None:
        if not self.weights:
            raise ValueError(f"suite {self.name!r}: give at least one task weight")
        if abs(sum(self.weights.values()) - 1.0) > 1e-9:
            raise ValueError(f"suite {self.name!r}: weights must sum to 1")


@dataclass(frozen=True)
class DiagnosticInfo(ComponentInfo):
    """A table (and optionally a chart) derived from scored results. ``load()`` returns a
    :class:`~bpb_core.interfaces.Diagnostic` class.

    Attributes:
        tasks: The tasks it looks at; reports show it when any of them ran.
    """

    tasks: tuple[str, ...] = ()
    kind: Kind = field(init=False, default="diagnostic")


@dataclass(frozen=True)
class Registered:
    """A record together with the plugin and distribution that supplied it."""

    info: ComponentInfo
    plugin: str
    distribution: str
    version: str
    module: str = ""

    @property
    def origin(self) -> str:
        """Who to blame for this component: the plugin (entry point name and the module it
        names) and its distribution, e.g. ``plugin 'echo' (bpb_echo.hooks) from bpb-echo 0.1``.
        """
        where = f" ({self.module})" if self.module and self.module != self.plugin else ""
        version = f" {self.version}" if self.version and self.version != "unknown" else ""
        return f"plugin {self.plugin!r}{where} from {self.distribution}{version}"
