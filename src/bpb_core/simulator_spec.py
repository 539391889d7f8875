"""Simulator specs: ``name`` or ``name:key=value,...``, a registered simulator and the options
it is built with (``pymunk:dt=0.0005``).

``bpb bench sim`` takes them as contestants, and a scene family's config may name its simulator
with one (:meth:`~bpb_core.interfaces.SceneFamily.simulator_name`): generation builds the
simulator with those options, and the manifest, which records the config, keeps them, so that
``bpb simulate`` and the oracle run the dataset's simulator as generation did.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bpb_core.errors import BadInput


@dataclass(frozen=True)
class SimulatorSpec:
    """A simulator name and its options, parsed from ``spec`` (``name:key=value,...``)."""

    spec: str
    name: str
    options: dict[str, Any]


def parse_spec(spec: str, flag: str) -> SimulatorSpec:
    """Parse ``name`` or ``name:key=value,...``; values become int, float or str. ``flag``
    names where the spec was given (``--contestant``, ``config: simulator``...). No name, an
    option that is not ``key=value``, or one given twice raises :class:`BadInput`:
    ``"{flag} 'x:dt': expected name or name:key=value,..."``."""
    name, _, rest = spec.strip().partition(":")
    options: dict[str, Any] = {}
    for item in filter(None, (part.strip() for part in rest.split(","))):
        key, eq, value = item.partition("=")
        if not eq or not key.strip() or key.strip() in options:
            name = ""
            break
        options[key.strip()] = _value(value.strip())
    if not name.strip():
        raise BadInput(f"{flag} {spec!r}: expected name or name:key=value,... (each key once)")
    return SimulatorSpec(spec.strip(), name.strip(), options)


def _value(text: str) -> int | float | str:
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text
