"""The one rule for reading a ball id or a wall name out of a model's answer.

Used both when a reply is validated (``parse``) and when a stored answer is scored, so a value is
read the same way everywhere: an integer, an integer-valued float (``3.0``) or an integer string
with optional sign and surrounding spaces (``" 3"``, ``"-1"``) is an id; booleans and anything
else are not. Wall names are read in any case with surrounding spaces.
"""

from __future__ import annotations

from bpb_tasks.billiards.scene import WALLS, Wall


def ball_id(value: object) -> int | None:
    """The ball id ``value`` stands for, or ``None``."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        return int(value) if value.is_integer() else None
    if isinstance(value, str):
        text = value.strip()
        digits = text[1:] if text[:1] in "+-" else text
        return int(text) if digits.isdigit() and digits.isascii() else None
    return None


def wall_name(value: object) -> Wall | None:
    """The upper-case wall ``value`` names, or ``None``."""
    if isinstance(value, str):
        name = value.strip().upper()
        for wall in WALLS:
            if wall == name:
                return wall
    return None
