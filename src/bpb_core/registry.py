"""Plugin discovery and the typed facade over it.

:func:`make_registry` builds a fresh :class:`Registry`; nothing is discovered at import time.
The registry is the only code that calls hook implementations.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from importlib import metadata
from typing import Any

import pluggy

from bpb_core import hookspecs
from bpb_core.errors import PluginError, UnknownName
from bpb_core.records import KINDS, ComponentInfo, Kind, Registered

ENTRY_POINT_GROUP = "bpb"
LOCAL = "<local>"


class PluginWarning(UserWarning):
    """A plugin could not be imported or its hook failed; the rest keeps working."""


@dataclass(frozen=True)
class PluginSource:
    """Where a registered plugin object came from."""

    name: str
    distribution: str
    version: str


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

    def load(self, kind: Kind, name: str) -> Any:
        """Import and return the component class or factory registered as ``name``."""
        return self.get(kind, name).info.load()

    def __iter__(self) -> Iterator[Registered]:
        for kind in KINDS:
            yield from self.entries(kind).values()

    # Typed conveniences used by the runner and the CLI.
    def task(self, name: str) -> Any:
        """A fresh instance of the task ``name``."""
        return self.load("task", name)()

    def simulator(self, name: str, **options: Any) -> Any:
        """A fresh instance of the simulator ``name`` built with ``options``."""
        return self.load("simulator", name)(**options)

    def scene_family(self, name: str) -> Any:
        """A fresh instance of the scene family ``name``."""
        return self.load("scene_family", name)()

    def scorer(self, name: str) -> Any:
        """A fresh instance of the scorer ``name``."""
        return self.load("scorer", name)()

    def scorers_for(self, task: str) -> list[Registered]:
        """Scorers bound to ``task``."""
        return [r for r in self.entries("scorer").values() if getattr(r.info, "task", "") == task]

    def adapter(self, spec: str, options: Any = None) -> Any:
        """Build the adapter for a ``name:model`` spec (split at the first colon)."""
        from bpb_core.adapters import AdapterOptions, split_spec

        name, model = split_spec(spec)
        factory = self.load("adapter", name)
        return factory(model, options if options is not None else AdapterOptions())


def _entry_point_plugins(group: str, problems: list[str]) -> Iterator[tuple[object, PluginSource]]:
    for ep in sorted(metadata.entry_points(group=group), key=lambda e: e.name):
        dist = ep.dist
        source = PluginSource(
            ep.name, dist.name if dist else LOCAL, dist.version if dist else "unknown"
        )
        try:
            yield ep.load(), source
        except Exception as exc:  # any import failure of a third-party plugin must not spread
            problems.append(
                f"plugin {ep.name!r} from {source.distribution} {source.version} "
                f"failed to import: {type(exc).__name__}: {exc}"
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
                records = list(impl.function() or ())
            except Exception as exc:
                problems.append(
                    f"plugin {source.name!r} from {source.distribution}: hook {hook_name} "
                    f"failed: {type(exc).__name__}: {exc}"
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
            f"plugin {source.name!r} from {source.distribution} returned {info!r} "
            f"from its {kind} hook; expected a {kind} record"
        )
    existing = table.get(info.name)
    if existing is not None:
        raise PluginError(
            f"two plugins register the {kind} {info.name!r}: "
            f"{existing.distribution} ({existing.plugin}) and {source.distribution} ({source.name})"
        )
    table[info.name] = Registered(info, source.name, source.distribution, source.version)


def make_registry(
    plugins: Iterable[object | tuple[object, PluginSource]] = (),
    *,
    entry_points: bool = True,
    group: str = ENTRY_POINT_GROUP,
) -> Registry:
    """Discover plugins and build a :class:`Registry`.

    Args:
        plugins: Extra plugin objects (modules or instances with hook implementations),
            optionally paired with a :class:`PluginSource`; used by tests and embedders.
        entry_points: Also load every plugin of the ``bpb`` entry-point group.
        group: Entry-point group to scan (tests point this at a private group).

    Raises:
        PluginError: Two plugins register the same name, or a hook name is misspelt.
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
            found.append((item, PluginSource(label, LOCAL, "unknown")))
    for plugin, source in found:
        if pm.is_registered(plugin):
            continue
        pm.register(plugin, name=f"{source.distribution}:{source.name}")
        sources[id(plugin)] = source
    try:
        pm.check_pending()
    except pluggy.PluginValidationError as exc:
        raise PluginError(f"plugin {exc.plugin!r}: {exc}") from None
    components = _collect(pm, sources, problems)
    for line in problems:
        warnings.warn(line, PluginWarning, stacklevel=2)
    return Registry(components, problems)
