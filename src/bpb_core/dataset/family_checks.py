"""A scene family's generation hooks, called checked as :mod:`bpb_core.plugin_calls` calls
others: each runs under :func:`~bpb_core.errors.blamed` and checks what it returns, so a
family's mistake is one line naming its plugin (:class:`~bpb_core.errors.PluginBug`, exit 3)
instead of a traceback, or an error blamed on the manifest or the user's config. A
:class:`~bpb_core.errors.BadInput` the family raises about the config passes through.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from bpb_core.capabilities import Calibrating, HorizonTally, Tallying
from bpb_core.dataset.manifest import HorizonSummary
from bpb_core.errors import PluginBug, blamed
from bpb_core.interfaces import SceneFamily
from bpb_core.plugin_calls import family_label, family_model, json_values


def checked_config(
    family: SceneFamily, origin: str, config: Any, horizons: Sequence[float]
) -> None:
    """``family.check_config(config, horizons)``: its ``BadInput`` passes through.

    Raises:
        PluginBug: It raised anything else, naming ``origin`` (who supplied the family).
    """
    with blamed(origin, f"{family_label(family)}: check_config()"):
        family.check_config(config, horizons)


def recorded_physics(family: SceneFamily, origin: str, config: Any) -> dict[str, Any]:
    """``family.physics(config)``, checked: a dict that JSON can hold (the manifest records it).

    Raises:
        PluginBug: It raised or returned something else, naming ``origin``.
    """
    what = f"{family_label(family)}: physics()"
    with blamed(origin, what):
        physics = family.physics(config)
    return json_values(origin, what, physics, "what dataset.json")


def new_tallies(
    family: SceneFamily, origin: str, config: Any, horizons: Sequence[float]
) -> dict[float, CheckedTally]:
    """A ``family.new_tally(config, h)`` per horizon (none when the family does not tally),
    checked: each has ``add()`` and ``summary()``, which the writer calls next, checked too.

    Raises:
        PluginBug: ``new_tally()`` raised or returned something else, naming ``origin``.
    """
    if not isinstance(family, Tallying):
        return {}
    tallies = {}
    for horizon in horizons:
        what = f"{family_label(family)}: new_tally({horizon:g})"
        with blamed(origin, what):
            tally = family.new_tally(config, horizon)
        if not all(callable(getattr(tally, name, None)) for name in ("add", "summary")):
            raise PluginBug(
                f"{origin}: {what} returned {type(tally).__name__}; expected a tally with "
                "add(row) and summary()"
            )
        tallies[horizon] = CheckedTally(tally, origin, f"{what}'s")
    return tallies


@dataclass(frozen=True)
class CheckedTally:
    """A family's tally whose ``add()`` and ``summary()`` are called checked (the family's own
    ``write_stats()`` takes ``tally`` back as it made it).

    Attributes:
        tally: What the family's ``new_tally()`` returned.
        origin: Who supplied the family.
        what: Whose tally it is (``scene family 'x': new_tally(3)'s``).
    """

    tally: HorizonTally
    origin: str
    what: str

    def add(self, row: Mapping[str, object]) -> None:
        """``tally.add(row)``.

        Raises:
            PluginBug: It raised, naming ``origin``.
        """
        with blamed(self.origin, f"{self.what} add()"):
            self.tally.add(row)

    def summary(self) -> dict[str, Any]:
        """``tally.summary()``, checked: a dict that JSON can hold (the manifest records it)
        whose fields are not the counts bpb keeps itself (``scenes``).

        Raises:
            PluginBug: It raised or returned something else, naming ``origin``.
        """
        what = f"{self.what} summary()"
        with blamed(self.origin, what):
            summary = self.tally.summary()
        fields = json_values(self.origin, what, summary, "what dataset.json")
        ours = sorted(set(fields) & set(HorizonSummary.model_fields))
        if ours:
            raise PluginBug(
                f"{self.origin}: {what} returned {ours[0]!r}, which bpb counts itself; "
                "expected the family's own fields"
            )
        return fields


def calibrated(
    family: Calibrating, origin: str, config: Any, results: Mapping[float, Any]
) -> tuple[Any, dict[str, Any]]:
    """``family.apply_calibration(config, results)``, checked: the calibrated config (an
    instance of the family's ``config_model``) and the manifest's record (a dict).

    Raises:
        PluginBug: It raised or returned something else, naming ``origin``.
    """
    what = f"{family_label(family)}: apply_calibration()"
    with blamed(origin, what):
        applied = family.apply_calibration(config, results)
    model = family_model(family, "config_model")
    if isinstance(applied, tuple) and len(applied) == 2:
        new, record = applied
        if (model is None or isinstance(new, model)) and isinstance(record, dict):
            return new, record
    got = type(applied).__name__
    if isinstance(applied, tuple) and len(applied) == 2:
        got = f"({', '.join(type(part).__name__ for part in applied)})"
    expected = "the config" if model is None else model.__name__
    raise PluginBug(
        f"{origin}: {what} returned {got}; expected ({expected}, a dict: the manifest's "
        "calibration record)"
    )
