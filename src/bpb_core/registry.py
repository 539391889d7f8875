"""Plugin discovery and the typed facade over it.

:func:`make_registry` builds a fresh :class:`Registry`; nothing is discovered at import time.
The registry is the only code that calls hook implementations.

Plugin hooks yield typed registration records. A record names a component and says how
to build it; ``load`` is called only when the component is used, so a plugin can register a
component backed by a heavy library (litellm, pymunk) at no import cost. Fields beyond ``name``,
``load`` and ``summary`` are plain data that bpb reads without loading the component (which
family a task asks about, which task a scorer scores).
"""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from importlib import metadata
from typing import TYPE_CHECKING, Any, Literal, cast, get_args

import pluggy

from bpb_core import hookspecs
from bpb_core.capabilities import UsesRegistry
from bpb_core.errors import BadInput, PluginBug, PluginError, UnknownName, blamed
from bpb_core.model_calls import AdapterOptions, adapter_problem, article, split_spec
from bpb_core.scored_units import check_scorer

if TYPE_CHECKING:
    from bpb_core.interfaces import Diagnostic, ModelAdapter, SceneFamily, Scorer, Simulator, Task

Kind = Literal[
    "task", "scene_family", "simulator", "adapter", "scorer", "suite", "diagnostic", "reference"
]
KINDS: tuple[Kind, ...] = get_args(Kind)


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
        name: The name users type (``analytic``, ``litellm``).
        load: Zero-argument callable returning the component class or factory.
        summary: One line for ``bpb plugins`` and ``bpb list``.
    """

    name: str
    load: Callable[[], Any] = field(default=lambda: None, repr=False, compare=False)
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
class Figure:
    """One score a publication states for a model.

    Attributes:
        model: The model as the publication names it. A run matches it when the model part of
            its adapter spec, or the model id the provider reported, is the same name after
            :func:`model_key` (``litellm:gpt-5.5`` and ``openai/gpt-5.5`` match ``GPT-5.5``).
        metric: A task or suite name (``q1``, ``total``).
        value: The stated score, in [0, 1].
        horizon: The horizon the score is for; ``None``: the mean over the reference's
            ``horizons``.
        where: Where the publication states it (a section).
    """

    model: str
    metric: str
    value: float
    horizon: float | None = None
    where: str = ""


def model_key(name: str) -> str:
    """``name`` without an adapter (``x:``) or provider (``x/``) prefix, in lower case, with
    dots and underscores as hyphens: how runs and published figures are matched."""
    bare = name.rpartition(":")[2].rpartition("/")[2]
    return bare.lower().replace(".", "-").replace("_", "-")


@dataclass(frozen=True)
class ReferenceInfo(ComponentInfo):
    """Scores a publication states (a paper's results), shown beside runs of the same models.
    Nothing is loaded: the figures are the reference.

    Attributes:
        source: The publication, as a citation line.
        figures: The scores it states (only those: nothing read off a chart).
        horizons: The horizons its means are over; a run compared to a mean must have them all.
    """

    source: str = ""
    figures: tuple[Figure, ...] = ()
    horizons: tuple[float, ...] = ()
    kind: Kind = field(init=False, default="reference")


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
        """Who to blame for this component (:attr:`PluginSource.origin`)."""
        return PluginSource(self.plugin, self.distribution, self.version, self.module).origin


ENTRY_POINT_GROUP = "bpb"
LOCAL = "<local>"


class PluginWarning(UserWarning):
    """A plugin could not be imported or its hook failed; the rest keeps working."""


@dataclass(frozen=True)
class PluginSource:
    """Where a registered plugin object came from: the entry point's name, its distribution
    and version, and the module the entry point names (``module``)."""

    name: str
    distribution: str
    version: str
    module: str = ""

    @property
    def origin(self) -> str:
        """Who to blame for what the plugin supplies: the plugin (entry point name and the module
        it names) and its distribution, e.g. ``plugin 'echo' (bpb_echo.hooks) from bpb-echo 0.1``.
        """
        where = f" ({self.module})" if self.module and self.module != self.name else ""
        version = f" {self.version}" if self.version and self.version != "unknown" else ""
        return f"plugin {self.name!r}{where} from {self.distribution}{version}"


class Registry:
    """Components supplied by all plugins, keyed by kind and name.

    Attributes:
        warnings: One line per plugin that failed to import or whose hook raised.
    """

    def __init__(self, components: dict[Kind, dict[str, Registered]], problems: list[str]) -> None:
        self._components = components
        self.warnings = problems

    def entries(self, kind: Kind) -> dict[str, Registered]:
        """All registered components of one kind, sorted by name."""
        return dict(sorted(self._components[kind].items()))

    def names(self, kind: Kind) -> list[str]:
        """Names registered for ``kind``, sorted."""
        return sorted(self._components[kind])

    def get(self, kind: Kind, name: str) -> Registered:
        """The record for ``name``; raises :class:`UnknownName` listing the known names."""
        try:
            return self._components[kind][name]
        except KeyError:
            raise UnknownName(kind.replace("_", " "), name, self._components[kind]) from None

    def origin(self, kind: Kind, name: str) -> str:
        """Who supplied ``name``: plugin, module and distribution, for one-line errors."""
        return self.get(kind, name).origin

    def load(self, kind: Kind, name: str) -> Any:
        """Import and return the component class or factory registered as ``name``; a loader that
        fails (a wrong ``lazy`` reference, an import error) is a :class:`PluginBug`."""
        entry = self.get(kind, name)
        with blamed(entry.origin, f"loading the {kind.replace('_', ' ')} {name!r}"):
            return entry.info.load()

    def build(self, kind: Kind, name: str) -> Any:
        """A fresh instance of the component class registered as ``name`` (a
        :class:`PluginBug` naming the plugin when loading or creating it fails)."""
        made = self.load(kind, name)
        with blamed(self.origin(kind, name), f"creating the {kind.replace('_', ' ')} {name!r}"):
            return made()

    def __iter__(self) -> Iterator[Registered]:
        for kind in KINDS:
            yield from self.entries(kind).values()

    # The typed facade: every component comes out as its interface.
    def task(self, name: str) -> Task:
        """A fresh instance of the task ``name``."""
        return cast("Task", self.build("task", name))

    def task_info(self, name: str) -> TaskInfo:
        """The record of task ``name`` (which family it asks about, whether it is a default)."""
        info = self.get("task", name).info
        assert isinstance(info, TaskInfo)
        return info

    def tasks_for(self, family: str, *, default_only: bool = False) -> list[str]:
        """Tasks asking about ``family``'s scenes (only the default ones with ``default_only``,
        or all of them when none is marked default), sorted by name."""
        infos = [
            r.info
            for r in self.entries("task").values()
            if isinstance(r.info, TaskInfo) and r.info.family == family
        ]
        chosen = [i for i in infos if i.default] if default_only else infos
        return [i.name for i in (chosen or infos)]

    def simulator(
        self,
        name: str,
        options: Mapping[str, Any] | None = None,
        *,
        names: Mapping[str, str] | None = None,
    ) -> Simulator:
        """A fresh instance of the simulator ``name`` built with ``options``.

        Args:
            options: Keyword arguments for the simulator's factory; a mapping, so that a
                simulator may take options of any name (``name``, ``names``).
            names: How the caller's user gives each option, for messages (``{"dt": "--dt"}``
                for ``bpb simulate``'s flags; default: as the simulator takes it).

        Raises:
            BadInput: The simulator does not take one of the options, or refuses a value: the
                message starts with the option as ``names`` names it (``--dt: must be ...``).
        """
        given, named = dict(options or {}), names or {}
        factory = self.load("simulator", name)
        try:
            with blamed(self.origin("simulator", name), f"creating the simulator {name!r}"):
                simulator: Simulator = factory(**given)
        except PluginBug as exc:
            if not isinstance(exc.__cause__, TypeError) or not given:
                raise
            shown = ", ".join(named.get(key, key) for key in given)
            why = exc.__cause__
            raise BadInput(f"simulator {name!r}: does not accept {shown}: {why}") from None
        except BadInput as exc:
            if exc.option not in named:
                raise
            raise BadInput(exc.naming(named)) from None
        return simulator

    def simulator_info(self, name: str) -> SimulatorInfo:
        """The record of simulator ``name`` (which family it simulates)."""
        info = self.get("simulator", name).info
        assert isinstance(info, SimulatorInfo)
        return info

    def scene_family(self, name: str) -> SceneFamily:
        """A fresh instance of the scene family ``name``."""
        return cast("SceneFamily", self.build("scene_family", name))

    def default_family(self) -> str:
        """The family marked default by its plugin (or the only one installed); a
        :class:`BadInput` when none or several are marked and more than one is installed."""
        infos = [r.info for r in self.entries("scene_family").values()]
        marked = [i.name for i in infos if isinstance(i, SceneFamilyInfo) and i.default]
        if len(marked) == 1:
            return marked[0]
        if len(infos) == 1:
            return infos[0].name
        known = ", ".join(i.name for i in infos) or "none installed"
        raise BadInput(f"--family: no single default scene family; choose one of: {known}")

    def scorer_for(self, task: str) -> Scorer:
        """A fresh instance of the scorer of ``task``.

        Raises:
            BadInput: No installed scorer scores ``task``.
            PluginBug: Its ``scene_rule`` or ``columns`` is unusable, naming the plugin.
        """
        entry = self.scorer_entry(task)
        scorer: Scorer = self.build("scorer", entry.info.name)
        check_scorer(scorer, entry.origin)
        return scorer

    def scorer_entry(self, task: str) -> Registered:
        """The record of the scorer of ``task`` (its name and who supplied it); a
        :class:`BadInput` when no installed scorer scores it."""
        for entry in self.entries("scorer").values():
            if isinstance(entry.info, ScorerInfo) and entry.info.task == task:
                return entry
        raise BadInput(f"task {task!r}: no installed scorer scores it")

    def adapter(
        self, spec: str, options: AdapterOptions | None = None, *, flag: str = "--adapter"
    ) -> ModelAdapter:
        """Build the adapter for a ``name:model`` spec (split at the first colon).

        ``flag`` names the spec in a message about it (``--adapter``, or a library parameter).

        Raises:
            BadInput: ``spec`` is not ``NAME:MODEL`` or names no installed adapter.
            PluginBug: The factory raised, or returned something without an async
                ``complete(request)``, naming the plugin.
        """
        name, model = split_spec(spec, flag)
        factory = self.load("adapter", name)
        with blamed(self.origin("adapter", name), f"the adapter factory for {spec!r}"):
            made = factory(model, options if options is not None else AdapterOptions())
        problem = adapter_problem(made)
        if problem is not None:
            raise PluginBug(
                f"{self.origin('adapter', name)}: the adapter factory for {spec!r} returned "
                f"{problem}; expected an object with an async complete(request)"
            )
        if isinstance(made, UsesRegistry):
            made.use_registry(self)
        adapter: ModelAdapter = made
        return adapter

    def offline_specs(self) -> list[str]:
        """``name:model`` of every listed model of every offline adapter."""
        return [
            f"{r.info.name}:{model}"
            for r in self.entries("adapter").values()
            if isinstance(r.info, AdapterInfo) and r.info.offline
            for model in r.info.models
        ]

    def references(self) -> list[ReferenceInfo]:
        """Every installed reference (published figures), sorted by name."""
        found = self.entries("reference").values()
        return [r.info for r in found if isinstance(r.info, ReferenceInfo)]

    def suites(self) -> list[SuiteInfo]:
        """Every installed suite, sorted by name."""
        return [r.info for r in self.entries("suite").values() if isinstance(r.info, SuiteInfo)]

    def diagnostics_for(self, tasks: Iterable[str]) -> list[Diagnostic]:
        """Fresh instances of the diagnostics that look at any of ``tasks``, sorted by name.

        Raises:
            PluginBug: One's ``percent`` or ``terminal`` is not a tuple of column names (a
                string would be read letter by letter), naming the plugin.
        """
        wanted = set(tasks)
        found: list[Diagnostic] = []
        for entry in self.entries("diagnostic").values():
            info = entry.info
            if isinstance(info, DiagnosticInfo) and wanted & set(info.tasks):
                made = self.build("diagnostic", info.name)
                _check_columns(made, entry.origin, info.name)
                found.append(made)
        return found


def _check_columns(diagnostic: object, origin: str, name: str) -> None:
    for attribute in ("percent", "terminal"):
        value = getattr(diagnostic, attribute, None)
        if not isinstance(value, tuple | list) or not all(isinstance(c, str) for c in value):
            raise PluginBug(
                f"{origin}: diagnostic {name!r}: {attribute} is {value!r}; expected a tuple of "
                "column names (str)"
            )


def _entry_point_plugins(group: str, problems: list[str]) -> Iterator[tuple[object, PluginSource]]:
    known: dict[int, tuple[str, str]] = {}  # a distribution's metadata is parsed once
    for ep in sorted(metadata.entry_points(group=group), key=lambda e: e.name):
        dist = ep.dist
        if dist is None:
            source = PluginSource(ep.name, LOCAL, "unknown", ep.value)
        else:
            if id(dist) not in known:
                known[id(dist)] = (dist.name, dist.version)
            source = PluginSource(ep.name, *known[id(dist)], ep.value)
        try:
            yield ep.load(), source
        except Exception as exc:  # any import failure of a third-party plugin must not spread
            problems.append(
                f"plugin {ep.name!r} from {source.distribution} {source.version} "
                f"failed to import: {type(exc).__name__}: {exc}"
            )


def _check_hook_names(pm: pluggy.PluginManager, sources: dict[int, PluginSource]) -> None:
    """Refuse a hook implementation bpb has no hook for (a misspelt ``bpb_model_adapter``),
    naming the plugin, its module and distribution."""
    for hook_name, caller in vars(pm.hook).items():
        if hook_name.startswith("_") or caller.has_spec():
            continue
        for impl in caller.get_hookimpls():
            if impl.optionalhook:
                continue
            known = ", ".join(hookspecs.HOOK_KINDS)
            raise PluginError(
                f"{sources[id(impl.plugin)].origin}: unknown hook {hook_name!r}; "
                f"bpb's hooks: {known}"
            )


def _collect(
    pm: pluggy.PluginManager, sources: dict[int, PluginSource], problems: list[str]
) -> dict[Kind, dict[str, Registered]]:
    components: dict[Kind, dict[str, Registered]] = {kind: {} for kind in KINDS}
    for hook_name, kind in hookspecs.HOOK_KINDS.items():
        caller = getattr(pm.hook, hook_name)
        for impl in caller.get_hookimpls():
            source = sources[id(impl.plugin)]
            try:
                returned = impl.function()
                if isinstance(returned, ComponentInfo):
                    raise PluginError(
                        f"{source.origin}: hook {hook_name} returned one {_RECORDS[kind]}; "
                        "yield each record (or return a list of them)"
                    )
                records = list(returned or ())
            except PluginError:
                raise
            except Exception as exc:
                problems.append(
                    f"{source.origin}: hook {hook_name} failed: {type(exc).__name__}: {exc}"
                )
                continue
            for info in records:
                _add(components[kind], kind, info, source)
    return components


def _add(
    table: dict[str, Registered], kind: Kind, info: ComponentInfo, source: PluginSource
) -> None:
    if not isinstance(info, ComponentInfo) or info.kind != kind:
        raise PluginError(
            f"{source.origin} returned {info!r} from its {kind.replace('_', ' ')} hook; "
            f"expected {article(kind)} {kind.replace('_', ' ')} record ({_RECORDS[kind]})"
        )
    existing = table.get(info.name)
    if existing is not None:
        raise PluginError(
            f"two plugins register the {kind} {info.name!r}: "
            f"{existing.distribution} ({existing.plugin}) and {source.distribution} ({source.name})"
        )
    table[info.name] = Registered(
        info, source.name, source.distribution, source.version, source.module
    )


def _check_one_scorer_per_task(scorers: dict[str, Registered]) -> None:
    """Refuse two scorers for one task (which one scored it would be an accident of sorting),
    naming both and who supplied them."""
    seen: dict[str, Registered] = {}
    for name, entry in sorted(scorers.items()):
        if not isinstance(entry.info, ScorerInfo):
            continue
        first = seen.setdefault(entry.info.task, entry)
        if first is not entry:
            raise PluginError(
                f"two scorers score the task {entry.info.task!r}: {first.info.name!r} of "
                f"{first.origin} and {name!r} of {entry.origin}"
            )


_RECORDS: dict[Kind, str] = {
    record.kind: record.__name__ for record in ComponentInfo.__subclasses__()
}


def make_registry(
    plugins: Iterable[object | tuple[object, PluginSource]] = (),
    *,
    entry_points: bool = True,
    group: str = ENTRY_POINT_GROUP,
    warn: bool = True,
) -> Registry:
    """Discover plugins and build a :class:`Registry`.

    Args:
        plugins: Extra plugin objects (modules or instances with hook implementations),
            optionally paired with a :class:`PluginSource`; used by tests and embedders.
        entry_points: Also load every plugin of the ``bpb`` entry-point group.
        group: Entry-point group to scan (tests point this at a private group).
        warn: Issue each problem (:attr:`Registry.warnings`) as a :class:`PluginWarning`; a
            caller that shows or has shown them itself passes ``False``.

    Raises:
        PluginError: Two plugins register the same name, two scorers score one task, or a hook
            name is misspelt.
    """
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    problems: list[str] = []
    sources: dict[int, PluginSource] = {}
    found: list[tuple[object, PluginSource]] = []
    if entry_points:
        found.extend(_entry_point_plugins(group, problems))
    for item in plugins:
        if isinstance(item, tuple):
            found.append(item)
        else:
            label = getattr(item, "__name__", type(item).__name__)
            found.append((item, PluginSource(label, LOCAL, "unknown", label)))
    for plugin, source in found:
        if pm.is_registered(plugin):
            continue
        pm.register(plugin, name=f"{source.distribution}:{source.name}")
        sources[id(plugin)] = source
    _check_hook_names(pm, sources)
    components = _collect(pm, sources, problems)
    _check_one_scorer_per_task(components["scorer"])
    for line in problems if warn else ():
        warnings.warn(line, PluginWarning, stacklevel=2)
    return Registry(components, problems)
