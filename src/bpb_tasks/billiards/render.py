"""The three scene images: the initial state, the state at the horizon and the trajectories.

All three share one canvas (:class:`~bpb_tasks.billiards.render_canvas.CanvasSpec`): the same
size, scale and ball radius, so they overlay exactly. They are drawn in palette mode (see
:mod:`bpb_tasks.billiards.render_palette`); :func:`render_pngs` returns encoded PNG bytes.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from PIL import Image, ImageDraw

from bpb_tasks.billiards import render_style as st
from bpb_tasks.billiards.config import DatasetConfig
from bpb_tasks.billiards.outcome import CUE_ID, Outcome
from bpb_tasks.billiards.png import encode_palette_png
from bpb_tasks.billiards.render_arrow import arrow_length
from bpb_tasks.billiards.render_canvas import CanvasSpec
from bpb_tasks.billiards.render_palette import (
    GHOST_ALPHA,
    base,
    header_y,
    palette_for,
    stamp,
    text_patch,
)
from bpb_tasks.billiards.render_trajectory import draw_markers, draw_paths
from bpb_tasks.billiards.scene import Scene

IMAGE_NAMES = ("init.png", "final.png", "trajectory.png")
Point = tuple[float, float]


def paste_balls(
    img: Image.Image, spec: CanvasSpec, balls: Iterable[tuple[int, Point]], alpha: int = 255
) -> None:
    """Draw ball ``id`` centred on table point ``pos`` for each ``(id, pos)`` of ``balls``
    (``img`` in palette mode)."""
    for ball_id, pos in balls:
        sprite, mask = stamp(spec, ball_id, alpha)
        px, py = spec.to_px(*pos)
        half = sprite.width // 2
        img.paste(sprite, (round(px) - half, round(py) - half), mask)


def header_note(img: Image.Image, spec: CanvasSpec, text: str) -> None:
    """Right-aligned grey note in the header line."""
    patch = text_patch(spec, text, st.font(round(16 * spec.scale)), st.MUTED, st.PAGE)
    x = spec.header_right - patch.width
    img.paste(patch, (x, round(header_y(spec) - patch.height / 2)))


def render_init(scene: Scene, spec: CanvasSpec) -> Image.Image:
    """The initial state: balls, then the cue velocity arrow above them (shortened to stay on
    the cloth, off rails and pockets) and its speed in m/s."""
    img = base(spec, "Initial state, t = 0 s").copy()
    paste_balls(img, spec, ((ball.id, ball.pos) for ball in scene.balls))
    label = _draw_velocity(img, spec, scene)
    if label is not None:
        _speed_label(img, spec, *label)
    header_note(img, spec, speed_note(math.hypot(*scene.ball(CUE_ID).vel)))
    return img


def speed_note(speed: float) -> str:
    """The initial image's header note stating the cue ball's speed."""
    return f"cue ball {CUE_ID} speed {speed:.3f} m/s"


def render_final(scene: Scene, outcome: Outcome, spec: CanvasSpec) -> Image.Image:
    """The state at the horizon; pocketed balls are absent and listed in the header."""
    img = base(spec, f"State at t = {outcome.horizon:g} s").copy()
    at = [
        (ball.id, outcome.positions.get(ball.id))
        for ball in sorted(scene.balls, key=lambda b: b.id)
    ]
    paste_balls(img, spec, ((i, pos) for i, pos in at if pos is not None))
    pocketed = [str(i) for i, pos in at if pos is None]
    noun = "ball" if len(pocketed) == 1 else "balls"
    header_note(
        img, spec, f"pocketed: {noun} {', '.join(pocketed)}" if pocketed else "no ball pocketed"
    )
    return img


def render_trajectory(scene: Scene, outcome: Outcome, spec: CanvasSpec) -> Image.Image:
    """Paths over [0, horizon], start positions faded, end positions solid, then the contact
    and pocketing markers above everything."""
    img = base(spec, f"Trajectories, t = 0 to {outcome.horizon:g} s", legend=True).copy()
    paste_balls(img, spec, ((ball.id, ball.pos) for ball in scene.balls), alpha=GHOST_ALPHA)
    draw_paths(img, spec, palette_for(spec), outcome)
    ends = ((ball.id, outcome.positions.get(ball.id)) for ball in scene.balls)
    paste_balls(img, spec, ((i, pos) for i, pos in ends if pos is not None))
    draw_markers(img, spec, palette_for(spec), outcome)
    return img


def _draw_velocity(
    img: Image.Image, spec: CanvasSpec, scene: Scene
) -> tuple[Point, Point, Point, str] | None:
    """Draw the cue arrow; return what its speed label needs (start, tip, direction, text)."""
    cue = scene.ball(CUE_ID)
    vx, vy = cue.vel
    speed = math.hypot(vx, vy)
    if speed == 0:
        return None
    ux, uy = vx / speed, vy / speed
    r = spec.radius_m
    wanted = 0.10 + 0.12 * min(speed, 3.0)  # metres; direction matters, the label gives speed
    length = arrow_length(spec, cue.pos, (ux, uy), wanted)
    start = spec.to_px(cue.pos[0] + ux * r * 1.15, cue.pos[1] + uy * r * 1.15)
    end = spec.to_px(cue.pos[0] + ux * (r + length), cue.pos[1] + uy * (r + length))
    pal = palette_for(spec)
    arrow(ImageDraw.Draw(img), start, end, spec.scale, pal.ink(st.ARROW), pal.ink(st.HALO))
    return start, end, (ux, -uy), f"{speed:.2f} m/s"


def arrow(
    draw: ImageDraw.ImageDraw, start: Point, end: Point, s: float, ink: int, halo: int
) -> None:
    """A thick arrow with a dark halo from ``start`` to ``end`` (pixels)."""
    dx, dy = end[0] - start[0], end[1] - start[1]
    n = math.hypot(dx, dy) or 1.0
    ux, uy = dx / n, dy / n
    head, wing = 16 * s, 8 * s
    back = (end[0] - ux * head, end[1] - uy * head)
    tip = [
        end,
        (back[0] - uy * wing, back[1] + ux * wing),
        (back[0] + uy * wing, back[1] - ux * wing),
    ]
    draw.line((start, back), fill=halo, width=round(7 * s))
    draw.polygon(_grow(tip, 3.2 * s), fill=halo)
    draw.line((start, back), fill=ink, width=round(4 * s))
    draw.polygon(tip, fill=ink)


def _grow(points: list[Point], by: float) -> list[Point]:
    cx = sum(p[0] for p in points) / len(points)
    cy = sum(p[1] for p in points) / len(points)
    out = []
    for x, y in points:
        d = math.hypot(x - cx, y - cy) or 1.0
        out.append((x + (x - cx) / d * by, y + (y - cy) / d * by))
    return out


def _speed_label(
    img: Image.Image, spec: CanvasSpec, start: Point, tip: Point, direction: Point, text: str
) -> None:
    """The speed beside the arrow: beyond its tip, else beside its shaft, else behind the
    ball; the first place that fits on the cloth without covering the arrow."""
    font = st.font(round(17 * spec.scale), bold=True)
    patch = text_patch(
        spec, text, font, st.INK, st.PAGE, pad=round(6 * spec.scale), outline=st.HALO
    )
    w, h = patch.size
    gap = 10 * spec.scale
    dx, dy = direction
    reach = abs(dx) * w / 2 + abs(dy) * h / 2 + gap  # centre to box edge along the arrow
    side = abs(dy) * w / 2 + abs(dx) * h / 2 + gap  # ... and across it
    mid = ((start[0] + tip[0]) / 2, (start[1] + tip[1]) / 2)
    ball = spec.radius_m * spec.ppm
    candidates = [
        (tip[0] + dx * reach, tip[1] + dy * reach),
        (mid[0] - dy * side, mid[1] + dx * side),
        (mid[0] + dy * side, mid[1] - dx * side),
        (start[0] - dx * (reach + 2.3 * ball), start[1] - dy * (reach + 2.3 * ball)),
    ]
    (x0, y0), (x1, y1) = spec.to_px(0, spec.height_m), spec.to_px(spec.width_m, 0)

    def fits(c: Point) -> bool:
        return x0 + w / 2 + 2 <= c[0] <= x1 - w / 2 - 2 and y0 + h / 2 + 2 <= c[1] <= y1 - h / 2 - 2

    cx, cy = next((c for c in candidates if fits(c)), candidates[0])
    cx = min(max(cx, x0 + w / 2 + 2), x1 - w / 2 - 2)  # keep it on the cloth, off the axes
    cy = min(max(cy, y0 + h / 2 + 2), y1 - h / 2 - 2)
    img.paste(patch, (round(cx - w / 2), round(cy - h / 2)))


def render_pngs(scene: Scene, outcome: Outcome, config: DatasetConfig) -> dict[str, bytes]:
    """``init.png``, ``final.png`` and ``trajectory.png`` of a simulated scene, encoded."""
    spec = CanvasSpec.from_config(config)
    level = config.image.compress_level
    return {
        "init.png": encode_palette_png(render_init(scene, spec), level),
        "final.png": encode_palette_png(render_final(scene, outcome, spec), level),
        "trajectory.png": encode_palette_png(render_trajectory(scene, outcome, spec), level),
    }
