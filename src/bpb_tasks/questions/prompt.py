"""The common prompt of the built-in tasks, built from the scene alone.

The text states the constants and laws of the scene's physics, the table coordinates, the ball
radius, the pockets and the horizon (SPEC section 5); each task adds its question, the JSON format
with an example, and the reply instruction (reasoning first or JSON only). Nothing here reads
ground truth: the functions take a :class:`~bpb_tasks.billiards.scene.Scene` and prompt options
only.
"""

from __future__ import annotations

import json

from bpb_core.interfaces import PromptOptions
from bpb_tasks.billiards.scene import Scene


def _num(value: float) -> str:
    return f"{value:g}"


def _point(xy: tuple[float, float]) -> str:
    return f"({_num(xy[0])}, {_num(xy[1])})"


def table_text(scene: Scene) -> str:
    """Table size, coordinates and walls."""
    w, h = _num(scene.table.width), _num(scene.table.height)
    return (
        f"Table: {w} m along x by {h} m along y, seen from above. The origin (0, 0) is the "
        f"bottom-left corner, x grows to the right and y grows upward. Walls: LEFT is x = 0, "
        f"RIGHT is x = {w}, BOTTOM is y = 0, TOP is y = {h}."
    )


def balls_text(scene: Scene, options: PromptOptions) -> str:
    """Ball count, radius, the cue ball, and where the initial state is shown."""
    ids = sorted(b.id for b in scene.balls)
    radius = _num(scene.physics.ball_radius)
    where = (
        "The image shows every ball with its id and the cue ball's velocity as an arrow "
        "labelled with its speed in m/s."
        if options.input_mode != "state"
        else "The initial state is given as JSON below."
    )
    return (
        f"Balls: {len(ids)} balls with ids {ids[0]}..{ids[-1]}, equal mass, radius "
        f"R = {radius} m. Ball 0 is the cue ball; at t = 0 only the cue ball moves, all others are "
        f"at rest. {where} A ball touches a wall when its centre is R from the wall, and two "
        f"balls touch when their centres are 2R apart."
    )


def pockets_text(scene: Scene) -> str:
    """Pocket positions and the pocketing rule."""
    pockets = scene.pockets
    if not pockets.centers or pockets.radius <= 0:
        return "Pockets: none; no ball can leave the table."
    centres = ", ".join(_point(c) for c in pockets.centers)
    return (
        f"Pockets: {len(pockets.centers)} pockets of radius {_num(pockets.radius)} m centred at "
        f"{centres}. A ball is pocketed the first instant its centre comes within "
        f"{_num(pockets.radius)} m of a pocket centre, and it leaves the table."
    )


def physics_text(scene: Scene) -> str:
    """Friction law, stop distance and collision law."""
    p = scene.physics
    restitution = (
        "perfectly elastic (the normal component of velocity is reversed)"
        if p.wall_restitution == 1
        else f"with restitution {_num(p.wall_restitution)} (normal component scaled by it)"
    )
    return (
        f"Friction: a moving ball decelerates at constant mu*g along its velocity, with "
        f"mu = {_num(p.mu)} and g = {_num(p.g)} m/s^2. After travelling a distance s its speed is "
        f"v(s) = sqrt(v0^2 - 2*mu*g*s); it stops after s_stop = v0^2 / (2*mu*g) and then stays at "
        f"rest until another ball hits it.\n"
        f"Collisions: ball-ball collisions are perfectly elastic and frictionless between equal "
        f"masses (the balls exchange the velocity components along the line of centres); wall "
        f"collisions are {restitution}. There is no spin."
    )


def state_json(scene: Scene) -> str:
    """The initial state as compact JSON (positions and velocities of every ball)."""
    balls = [
        {"id": b.id, "pos": list(b.pos), "vel": list(b.vel)}
        for b in sorted(scene.balls, key=lambda b: b.id)
    ]
    return json.dumps({"balls": balls})


def common_prompt(scene: Scene, options: PromptOptions) -> str:
    """Everything every task states before its question."""
    parts = [
        f"You are looking at a billiards table (scene {scene.scene_id}). Predict what happens "
        f"from t = 0 until t = {_num(scene.horizon)} s using the physics below.",
        table_text(scene),
        balls_text(scene, options),
        pockets_text(scene),
        physics_text(scene),
        f"Horizon: t = {_num(scene.horizon)} s. Anything that happens at or before "
        f"t = {_num(scene.horizon)} s counts.",
    ]
    if options.input_mode in ("image+state", "state"):
        parts.append(f"Initial state at t = 0 (metres, m/s): {state_json(scene)}")
    return "\n\n".join(parts)


def reply_instruction(options: PromptOptions, example: str) -> str:
    """How to reply: reasoning then JSON, or JSON only; stronger after a malformed answer."""
    if options.cot:
        text = (
            "Think step by step, then end your reply with the final answer as one JSON object "
            "in exactly the format above."
        )
    else:
        text = "Reply with the JSON object only, in exactly the format above, and no other text."
    if options.escalation >= 1:
        text += (
            "\nIMPORTANT: a previous reply to this question could not be read. The reply must "
            "contain one complete, valid JSON object (double quotes, no comments, no trailing "
            "commas) covering every item listed."
        )
    if options.escalation >= 2:
        text += f"\nReturn exactly this shape with your own values:\n{example}"
    return text
