"""A scene read from the image and prompt a model is given, and how far it is from the truth.

:func:`perceive` returns a valid :class:`~bpb_tasks.billiards.scene.model.Scene`: centres that come
out overlapping or off the table by a rounding are moved apart or inside (the renderer pastes each
ball at a whole pixel, so a touching pair may be read up to a pixel too close).

What even a perfect reader of ``init.png`` could get right (``baseline:vision``'s ceiling): the
renderer pastes every ball at a whole pixel, so the image cannot place a centre closer than
half a pixel. :func:`perception_ceiling` moves every true centre to the pixel it is drawn at
(the grid read from the image itself, so any ``image.px_per_m`` is handled), keeps the true
velocities, simulates that scene and says which labels survive: ``pixel_ceiling_q1_set`` (every
Q1 label) and ``pixel_ceiling_q2`` (the wall set). Over a run the report shows their share by
horizon beside the accuracy of whatever read the image.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from bpb_core.errors import BpbError
from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.scene.model import Ball, Scene
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.billiards.truth.outcome import CUE_ID
from bpb_tasks.billiards.vision.balls import find_balls, read_direction, read_speed
from bpb_tasks.billiards.vision.frame import (
    PerceptionFailed,
    PromptFacts,
    canvas_of,
    find_frame,
    image_keys,
    read_prompt,
)

Point = tuple[float, float]
SEPARATION = 1e-6  # metres added when moving a pair apart, beyond touching


def perceive(png: bytes, prompt: str) -> Scene:
    """The scene shown in ``png`` as described by ``prompt``.

    Raises:
        PerceptionFailed: Something could not be read (the message says what).
    """
    facts = read_prompt(prompt)
    keys = image_keys(png)
    frame = find_frame(keys, facts)
    spec = canvas_of(frame, facts, (keys.shape[1], keys.shape[0]))
    pixels = find_balls(keys, spec, facts.ids)
    if CUE_ID not in pixels:
        raise PerceptionFailed("the prompt names no cue ball 0")
    speed = read_speed(keys, spec)
    angle = read_direction(keys, spec, pixels[CUE_ID])
    centres = _separate({i: frame.to_table(*p) for i, p in pixels.items()}, facts)
    balls = [
        Ball(
            id=i,
            pos=centres[i],
            vel=(speed * math.cos(angle), speed * math.sin(angle)) if i == CUE_ID else (0.0, 0.0),
        )
        for i in facts.ids
    ]
    try:
        return Scene(
            scene_id=facts.scene_id,
            horizon=facts.horizon,
            table=facts.table,
            physics=facts.physics,
            pockets=facts.pockets,
            balls=balls,
        )
    except ValueError as exc:
        raise PerceptionFailed(f"the balls read do not make a valid scene: {exc}") from None


def _separate(centres: dict[int, Point], facts: PromptFacts) -> dict[int, Point]:
    """Centres moved inside the table and apart to at least touching distance."""
    r = facts.physics.ball_radius
    w, h = facts.table.width, facts.table.height
    out = {i: (min(max(x, r), w - r), min(max(y, r), h - r)) for i, (x, y) in centres.items()}
    ids = sorted(out)
    for _ in range(20):
        moved = False
        for n, a in enumerate(ids):
            for b in ids[n + 1 :]:
                (ax, ay), (bx, by) = out[a], out[b]
                gap = math.dist(out[a], out[b])
                if gap >= 2 * r:
                    continue
                ux, uy = ((bx - ax) / gap, (by - ay) / gap) if gap > 0 else (1.0, 0.0)
                push = (2 * r - gap) / 2 + SEPARATION
                out[a] = (ax - ux * push, ay - uy * push)
                out[b] = (bx + ux * push, by + uy * push)
                moved = True
        out = {i: (min(max(x, r), w - r), min(max(y, r), h - r)) for i, (x, y) in out.items()}
        if not moved:
            break
    return out


def perception_error(perceived: Scene, scene: Scene) -> dict[str, float]:
    """Centre error (mm, mean and max over balls), cue speed error (m/s) and cue direction
    error (degrees) of ``perceived`` against the true ``scene``."""
    errors = [
        1000 * math.dist(perceived.ball(b.id).pos, b.pos)
        for b in scene.balls
        if any(p.id == b.id for p in perceived.balls)
    ]
    seen, true = perceived.ball(CUE_ID).vel, scene.ball(CUE_ID).vel
    turn = math.atan2(seen[1], seen[0]) - math.atan2(true[1], true[0])
    return {
        "centre_error_mm": round(sum(errors) / len(errors), 4),
        "centre_error_max_mm": round(max(errors), 4),
        "speed_error_mps": round(abs(math.hypot(*seen) - math.hypot(*true)), 6),
        "angle_error_deg": round(abs(math.degrees(math.remainder(turn, math.tau))), 4),
    }


def snapped(scene: Scene, spec: CanvasSpec) -> Scene:
    """``scene`` with every centre moved to the whole pixel its sprite is pasted at (no
    validation: two balls may then overlap by up to a pixel)."""
    balls = []
    for ball in scene.balls:
        px, py = spec.to_px(*ball.pos)
        x = (round(px) - spec.left) / spec.ppm
        y = spec.height_m - (round(py) - spec.top) / spec.ppm
        balls.append(ball.model_copy(update={"pos": (x, y)}))
    return scene.model_copy(update={"balls": balls})


def perception_ceiling(
    png: bytes, prompt: str, scene: Scene, truth_of: Callable[[Scene], FinalState]
) -> dict[str, bool]:
    """Whether the pixel-snapped ``scene`` keeps every Q1 label and the Q2 wall set of the true
    one (``truth_of`` gives a scene's ground truth); empty when the snapped scene cannot be
    simulated."""
    truth = truth_of(scene)
    try:
        facts, keys = read_prompt(prompt), image_keys(png)
        spec = canvas_of(find_frame(keys, facts), facts, (keys.shape[1], keys.shape[0]))
        seen = truth_of(snapped(scene, spec))
    except (ValueError, BpbError):  # the simulator refused the snapped scene (an event cap)
        return {}
    return {
        "pixel_ceiling_q1_set": seen.q1 == truth.q1,
        "pixel_ceiling_q2": seen.q2 == truth.q2,
    }
