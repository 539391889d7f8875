"""The questions answered by people in the browser (``bpb human``): what each form shows and how
its posted fields become the task's answer.

Q1 and Q2 are ticks (a ticked ball or wall is ``T``, the rest ``F``); Q3 places every ball by
dragging its marker over the scene image, onto a pocket for a pocketed ball. The image's frame
(origin and scale) is read from its axes, as ``baseline:vision`` reads it, so the markers sit on
the balls whatever the dataset's image settings. The templates are ``forms/<task>.html``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from importlib import resources
from typing import Any

from bpb_tasks.billiards.render import canvas as st
from bpb_tasks.billiards.scene.model import Scene

POCKETED = "pocket"
MAX_VALUE = 64  # characters a posted value may have


def template(name: str) -> str:
    """The Jinja2 source of ``forms/<name>.html``."""
    return resources.files("bpb_tasks.questions").joinpath(f"forms/{name}.html").read_text()


def read_ticks(fields: Mapping[str, str], names: Sequence[str]) -> set[str]:
    """The ticked names among ``names``; any other field or value is an error."""
    for key, value in fields.items():
        if key not in names:
            raise ValueError(f"{key}: not a field of this form")
        if value != "T":
            raise ValueError(f"{key}: a ticked box posts T, got {value[:MAX_VALUE]!r}")
    return set(fields)


def colour(ball_id: int) -> str:
    """CSS colour of ball ``ball_id`` as the renderer draws it."""
    r, g, b = st.ball_colour(ball_id)
    return f"#{r:02x}{g:02x}{b:02x}"


def _frame(scene: Scene, image: bytes | None) -> dict[str, float] | None:
    from bpb_tasks.billiards.vision.frame import (
        PerceptionFailed,
        PromptFacts,
        find_frame,
        image_keys,
    )

    if image is None:
        return None
    ids = tuple(b.id for b in scene.balls)
    facts = PromptFacts(
        scene.scene_id, scene.horizon, scene.table, scene.physics, scene.pockets, ids
    )
    try:
        frame = find_frame(image_keys(image), facts)
    except PerceptionFailed:
        return None
    return {"x0": frame.x0, "y0": frame.y0, "ppm": frame.ppm}


def drag_context(scene: Scene, image: bytes | None) -> dict[str, Any]:
    """Markers at the balls' starting pixels and pocket drop zones (``frame`` is ``None`` when
    the image has no readable axes: the form then asks for numbers)."""
    balls = [
        {"id": b.id, "x": b.pos[0], "y": b.pos[1], "colour": colour(b.id)} for b in scene.balls
    ]
    context: dict[str, Any] = {
        "balls": sorted(balls, key=lambda b: int(b["id"])),
        "table": [scene.table.width, scene.table.height],
        "radius": scene.physics.ball_radius,
        "pockets": [list(c) for c in scene.pockets.centers],
        "pocket_radius": scene.pockets.radius,
        "frame": _frame(scene, image),
        "horizon": f"{scene.horizon:g}",
    }
    return context


def _position(key: str, value: str, scene: Scene) -> list[float] | None:
    if value == POCKETED:
        return None
    parts = value.split(",")
    try:
        x, y = (float(p) for p in parts) if len(parts) == 2 else (math.nan, math.nan)
    except ValueError:
        x = y = math.nan
    if not (math.isfinite(x) and math.isfinite(y)):
        shown = value[:MAX_VALUE]
        raise ValueError(f"{key}: expected 'x,y' in metres or {POCKETED!r}, got {shown!r}")
    if not (0 <= x <= scene.table.width and 0 <= y <= scene.table.height):
        raise ValueError(f"{key}: ({x:g}, {y:g}) is off the table")
    return [round(x, 4), round(y, 4)]


def read_positions(fields: Mapping[str, str], scene: Scene) -> dict[str, Any]:
    """Q3's answer from the fields ``pos<id>`` (one per ball, ``x,y`` or ``pocket``)."""
    names = {f"pos{b.id}": b.id for b in scene.balls}
    for key in fields:
        if key not in names:
            raise ValueError(f"{key}: not a field of this form")
    missing = [key for key in names if key not in fields]
    if missing:
        raise ValueError(f"{missing[0]}: missing (every ball needs a place)")
    predictions = [{"id": i, "pos": _position(k, fields[k], scene)} for k, i in names.items()]
    return {"predictions": sorted(predictions, key=lambda p: int(p["id"]))}
