"""The facts the common prompt states in words: horizon, table, ball ids, radius, friction,
restitution and pockets (see :mod:`bpb_tasks.questions.prompt`, whose wording this reads)."""

from __future__ import annotations

import re
from dataclasses import dataclass

from bpb_tasks.billiards.scene import Physics, Pockets, Table

_NUM = r"([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)"


class PerceptionFailed(ValueError):
    """The image or the prompt could not be read; the message says what was missing."""


@dataclass(frozen=True)
class PromptFacts:
    """What the prompt says about the scene besides the picture."""

    scene_id: str
    horizon: float
    table: Table
    physics: Physics
    pockets: Pockets
    ids: tuple[int, ...]


def _find(pattern: str, text: str, what: str) -> re.Match[str]:
    match = re.search(pattern, text)
    if match is None:
        raise PerceptionFailed(f"the prompt does not state the {what}")
    return match


def _pockets(text: str) -> Pockets:
    if "Pockets: none" in text:
        return Pockets(radius=0.0, centers=[])
    stated = rf"Pockets: \d+ pockets of radius {_NUM} m centred at (.*?)\. A ball"
    match = _find(stated, text, "pockets")
    centres = [(float(x), float(y)) for x, y in re.findall(rf"\({_NUM}, {_NUM}\)", match.group(2))]
    return Pockets(radius=float(match.group(1)), centers=centres)


def read_prompt(text: str) -> PromptFacts:
    """The scene's stated facts.

    Raises:
        PerceptionFailed: A fact is missing from ``text`` (names it).
    """
    scene_id = _find(r"\(scene ([^)\s]+)\)", text, "scene id").group(1)
    horizon = float(_find(rf"until t = {_NUM} s", text, "horizon").group(1))
    size = _find(rf"Table: {_NUM} m along x by {_NUM} m along y", text, "table size")
    ids = _find(r"Balls: (\d+) balls with ids (\d+)\.\.(\d+)", text, "ball ids")
    radius = float(_find(rf"radius R = {_NUM} m", text, "ball radius").group(1))
    friction = _find(rf"mu = {_NUM} and g = {_NUM} m/s", text, "friction")
    stated = re.search(rf"wall collisions are with restitution {_NUM}", text)
    restitution = float(stated.group(1)) if stated else 1.0
    return PromptFacts(
        scene_id,
        horizon,
        Table(width=float(size.group(1)), height=float(size.group(2))),
        Physics(
            ball_radius=radius,
            mu=float(friction.group(1)),
            g=float(friction.group(2)),
            wall_restitution=restitution,
        ),
        _pockets(text),
        tuple(range(int(ids.group(2)), int(ids.group(3)) + 1)),
    )
