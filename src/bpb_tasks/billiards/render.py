"""The three scene images: the initial state, the state at the horizon and the trajectories.

All three share one canvas (:class:`~bpb_tasks.billiards.render_canvas.CanvasSpec`): the same
size, scale and ball radius, so they overlay exactly. :func:`render_pngs` returns encoded PNG
bytes ready to be written.
"""

from __future__ import annotations

import io
import math

from PIL import Image, ImageDraw

from bpb_core.outcome import CUE_ID, Outcome
from bpb_core.scene import Scene
from bpb_tasks.billiards import render_style as st
from bpb_tasks.billiards.config import DatasetConfig
from bpb_tasks.billiards.render_canvas import CanvasSpec, background, to_palette
from bpb_tasks.billiards.render_trajectory import draw_trajectories

IMAGE_NAMES = ("init.png", "final.png", "trajectory.png")


def paste_ball(
    img: Image.Image, spec: CanvasSpec, ball_id: int, pos: tuple[float, float], alpha: int = 255
) -> None:
    """Draw ball ``ball_id`` centred on table point ``pos``."""
    sprite = st.ball_sprite(ball_id, spec.radius_px, alpha)
    px, py = spec.to_px(*pos)
    half = sprite.width // 2
    img.paste(sprite, (round(px) - half, round(py) - half), sprite)


def title(img: Image.Image, spec: CanvasSpec, left: str, right: str = "") -> None:
    """Write the header line above the table: ``left`` in bold, ``right`` right-aligned."""
    draw = ImageDraw.Draw(img)
    s = spec.scale
    y = spec.top / 2 - 14 * s
    draw.text(
        (spec.left - 60 * s, y), left, fill=st.INK, font=st.font(round(19 * s), True), anchor="lm"
    )
    if right:
        x = img.width - spec.right
        draw.text((x, y), right, fill=st.MUTED, font=st.font(round(16 * s)), anchor="rm")


def render_init(scene: Scene, spec: CanvasSpec) -> Image.Image:
    """The initial state: balls, the cue velocity arrow and its speed in m/s (RGB)."""
    img = background(spec).copy()
    label = _draw_velocity(img, spec, scene)  # under the balls, so no id is hidden
    for ball in scene.balls:
        paste_ball(img, spec, ball.id, ball.pos)
    speed = math.hypot(*scene.ball(CUE_ID).vel)
    if label is not None:
        _speed_label(img, spec, *label)
    title(img, spec, "Initial state, t = 0 s", f"cue ball 0 speed {speed:.3f} m/s")
    return img


def render_final(scene: Scene, outcome: Outcome, spec: CanvasSpec) -> Image.Image:
    """The state at the horizon; pocketed balls are absent and listed in the header (RGB)."""
    img = background(spec).copy()
    pocketed = []
    for ball in sorted(scene.balls, key=lambda b: b.id):
        pos = outcome.positions.get(ball.id)
        if pos is None:
            pocketed.append(str(ball.id))
        else:
            paste_ball(img, spec, ball.id, pos)
    noun = "ball" if len(pocketed) == 1 else "balls"
    note = f"pocketed: {noun} {', '.join(pocketed)}" if pocketed else "no ball pocketed"
    title(img, spec, f"State at t = {outcome.horizon:g} s", note)
    return img


def render_trajectory(scene: Scene, outcome: Outcome, spec: CanvasSpec) -> Image.Image:
    """Paths over [0, horizon], start positions faded, end positions solid, events marked."""
    img = background(spec).copy()
    for ball in scene.balls:
        paste_ball(img, spec, ball.id, ball.pos, alpha=110)
    draw_trajectories(img, spec, outcome)
    for ball in scene.balls:
        pos = outcome.positions.get(ball.id)
        if pos is not None:
            paste_ball(img, spec, ball.id, pos)
    title(img, spec, f"Trajectories, t = 0 to {outcome.horizon:g} s", "")
    return img


def _draw_velocity(
    img: Image.Image, spec: CanvasSpec, scene: Scene
) -> tuple[tuple[float, float], tuple[float, float], str] | None:
    """Draw the cue arrow; return where its speed label goes (tip, direction, text)."""
    cue = scene.ball(CUE_ID)
    vx, vy = cue.vel
    speed = math.hypot(vx, vy)
    if speed == 0:
        return None
    ux, uy = vx / speed, vy / speed
    r = spec.radius_m
    length = 0.10 + 0.12 * min(speed, 3.0)  # metres; direction matters, the label gives speed
    start = spec.to_px(cue.pos[0] + ux * r * 1.15, cue.pos[1] + uy * r * 1.15)
    end = spec.to_px(cue.pos[0] + ux * (r + length), cue.pos[1] + uy * (r + length))
    arrow(ImageDraw.Draw(img), start, end, spec.scale)
    return end, (ux, -uy), f"{speed:.2f} m/s"


def arrow(
    draw: ImageDraw.ImageDraw, start: tuple[float, float], end: tuple[float, float], s: float
) -> None:
    """A thick arrow with a dark halo from ``start`` to ``end`` (pixels)."""
    dx, dy = end[0] - start[0], end[1] - start[1]
    n = math.hypot(dx, dy) or 1.0
    ux, uy = dx / n, dy / n
    head, wing = 16 * s, 8 * s
    base = (end[0] - ux * head, end[1] - uy * head)
    tip = [
        end,
        (base[0] - uy * wing, base[1] + ux * wing),
        (base[0] + uy * wing, base[1] - ux * wing),
    ]
    draw.line((start, base), fill=st.HALO, width=round(7 * s))
    draw.polygon(_grow(tip, 2.0 * s), fill=st.HALO)
    draw.line((start, base), fill=st.ARROW, width=round(4 * s))
    draw.polygon(tip, fill=st.ARROW)


def _grow(points: list[tuple[float, float]], by: float) -> list[tuple[float, float]]:
    cx = sum(p[0] for p in points) / len(points)
    cy = sum(p[1] for p in points) / len(points)
    out = []
    for x, y in points:
        d = math.hypot(x - cx, y - cy) or 1.0
        out.append((x + (x - cx) / d * by * 1.6, y + (y - cy) / d * by * 1.6))
    return out


def _speed_label(
    img: Image.Image,
    spec: CanvasSpec,
    anchor: tuple[float, float],
    direction: tuple[float, float],
    text: str,
) -> None:
    draw = ImageDraw.Draw(img)
    font = st.font(round(17 * spec.scale), bold=True)
    box = draw.textbbox((0, 0), text, font=font)
    w, h = box[2] - box[0] + 12 * spec.scale, box[3] - box[1] + 10 * spec.scale
    gap = 10 * spec.scale
    cx = anchor[0] + direction[0] * (w / 2 + gap)
    cy = anchor[1] + direction[1] * (h / 2 + gap)
    cx = min(max(cx, w / 2 + 2), img.width - w / 2 - 2)
    cy = min(max(cy, h / 2 + 2), img.height - h / 2 - 2)
    rect = (cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2)
    draw.rounded_rectangle(rect, radius=5 * spec.scale, fill=st.PAGE, outline=st.HALO, width=1)
    draw.text((cx, cy), text, fill=st.INK, font=font, anchor="mm")


def encode_png(img: Image.Image, spec: CanvasSpec, ball_ids: tuple[int, ...], level: int) -> bytes:
    """PNG bytes of ``img`` as an 8-bit palette image (deterministic for equal input)."""
    out = io.BytesIO()
    to_palette(img, spec, ball_ids).save(out, format="PNG", compress_level=level)
    return out.getvalue()


def render_pngs(scene: Scene, outcome: Outcome, config: DatasetConfig) -> dict[str, bytes]:
    """``init.png``, ``final.png`` and ``trajectory.png`` of a simulated scene, encoded."""
    spec = CanvasSpec.from_config(config)
    ids = tuple(sorted(b.id for b in scene.balls))
    level = config.image.compress_level
    images = (
        render_init(scene, spec),
        render_final(scene, outcome, spec),
        render_trajectory(scene, outcome, spec),
    )
    return {
        name: encode_png(img, spec, ids, level)
        for name, img in zip(IMAGE_NAMES, images, strict=True)
    }
