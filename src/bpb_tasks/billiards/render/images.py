"""The three scene images: the initial state, the state at the horizon and the trajectories.

All three share one canvas (:class:`~bpb_tasks.billiards.render.canvas.CanvasSpec`): the same
size, scale and ball radius, so they overlay exactly. They are drawn in palette mode (see
:mod:`bpb_tasks.billiards.render.palette`); :func:`render_pngs` returns encoded PNG bytes.

The cue velocity arrow of ``init.png`` is the longest arrow, at most the wanted length, whose
shaft stays on the cloth and off the pockets and whose head keeps a clearance. A candidate length
is checked at points every 5 mm along the arrow (:func:`_clear`). The check tries the tip first
(where a too-long arrow fails) and then proves the whole shaft clear from its two ends (the shaft
is straight, so it stays in the box its ends are in, and it is far from a pocket whose distance
to the segment is larger than the pocket circle); only when the proof is not certain by a margin
far above rounding error are the points checked one by one. The answer is the same as checking
every point, so the images do not change.

The trajectory image draws each :class:`~bpb_tasks.billiards.truth.outcome.Segment` straight
(friction acts along the velocity), so a path is a polyline through the segment end points.
Ball-ball contacts are marked by a red ring at the contact point, wall contacts by a blue diamond at
the centre, pocketings by a white cross.

The failure gallery's picture of a scene (:func:`scene_picture`) is its ``trajectory.png`` (or
``init.png``), mapped to table metres with the image geometry recorded in ``dataset.json``
(``config.image``); when the images or the geometry are missing, a plain table is drawn instead.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from pathlib import Path

from PIL import Image, ImageDraw

from bpb_core.layout import MANIFEST
from bpb_core.picture import ScenePicture, font as gallery_font
from bpb_tasks.billiards.render import canvas as st
from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.render.palette import (
    GHOST_ALPHA,
    Palette,
    base,
    header_y,
    palette_for,
    stamp,
    text_patch,
)
from bpb_tasks.billiards.render.png import encode_palette_png
from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.truth.outcome import CUE_ID, Outcome, Segment

IMAGE_NAMES = ("init.png", "final.png", "trajectory.png")
Point = tuple[float, float]

ARROW_CLEARANCE = 0.012
"""Metres the arrow keeps from the cushions and from every pocket's edge."""
ARROW_MIN = 0.05
"""The shortest arrow drawn (metres beyond the ball), even where nothing longer fits."""
_SAFE = 1e-9
"""Metres of margin for the two-ends proof (rounding errors are about 1e-16 m)."""


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


def arrow_length(spec: CanvasSpec, pos: Point, direction: Point, wanted: float) -> float:
    """The longest arrow (metres beyond the cue ball's edge), at most ``wanted``, whose shaft
    and head stay on the cloth and off the pockets (down to :data:`ARROW_MIN`)."""
    length = wanted
    while length > ARROW_MIN and not _clear(spec, pos, direction, length):
        length -= 0.005
    return max(length, ARROW_MIN)


def _clear(spec: CanvasSpec, pos: Point, direction: Point, length: float) -> bool:
    """Whether the shaft stays on the cloth and off the pockets, and the head (its
    half-width plus :data:`ARROW_CLEARANCE`) too."""
    head = 10 * spec.scale / spec.ppm + ARROW_CLEARANCE  # the head's half-width, in metres
    r = spec.radius_m
    steps = max(2, math.ceil(length / 0.005))

    def point(k: int) -> Point:
        d = r * 1.15 + (length + r - r * 1.15) * k / steps
        return pos[0] + direction[0] * d, pos[1] + direction[1] * d

    tip = point(steps)
    if not _point_clear(spec, tip, head):
        return False
    first = point(0)
    if _surely_clear(spec, first, tip, head):
        return True
    return all(_point_clear(spec, point(k), 0.0) for k in range(steps))


def _point_clear(spec: CanvasSpec, p: Point, room: float) -> bool:
    """Whether ``p`` is ``room`` inside the cushions and ``room`` off every pocket circle."""
    x, y = p
    if not (room <= x <= spec.width_m - room and room <= y <= spec.height_m - room):
        return False
    limit = spec.pocket_radius_m + room
    for px, py in spec.pockets:
        dx, dy = x - px, y - py
        # hypot(dx, dy) >= |dx| and >= |dy|: only a pocket this close in x and y can be hit
        if -limit < dx < limit and -limit < dy < limit and math.hypot(dx, dy) < limit:
            return False
    return True


def _surely_clear(spec: CanvasSpec, a: Point, b: Point, head: float) -> bool:
    """Whether every point of segment ``a``-``b`` is clear (room 0), with :data:`_SAFE` to
    spare; ``False`` means "not proven", not "blocked"."""
    lo, hi = _SAFE, spec.width_m - _SAFE
    if not (lo <= min(a[0], b[0]) and max(a[0], b[0]) <= hi):
        return False
    hi = spec.height_m - _SAFE
    if not (lo <= min(a[1], b[1]) and max(a[1], b[1]) <= hi):
        return False
    limit = spec.pocket_radius_m + head + _SAFE
    return all(_segment_distance(a, b, c) > limit for c in spec.pockets)


def _segment_distance(a: Point, b: Point, c: Point) -> float:
    """Distance from ``c`` to the segment ``a``-``b``."""
    ex, ey = b[0] - a[0], b[1] - a[1]
    cx, cy = c[0] - a[0], c[1] - a[1]
    norm = ex * ex + ey * ey
    t = 0.0 if norm == 0 else min(1.0, max(0.0, (cx * ex + cy * ey) / norm))
    return math.hypot(cx - t * ex, cy - t * ey)


def segment_end(seg: Segment) -> Point:
    """Where the ball of ``seg`` is at ``seg.t1`` (or where it stopped, if earlier)."""
    speed = math.hypot(*seg.vel)
    dt = seg.t1 - seg.t0
    if speed == 0 or dt <= 0:
        return seg.pos
    if seg.decel > 0:
        dt = min(dt, speed / seg.decel)
    dist = speed * dt - 0.5 * seg.decel * dt * dt
    return seg.pos[0] + seg.vel[0] / speed * dist, seg.pos[1] + seg.vel[1] / speed * dist


def draw_paths(img: Image.Image, spec: CanvasSpec, pal: Palette, outcome: Outcome) -> None:
    """Draw every moving ball's path, the cue ball's last (on top): a polyline through the start
    of each moving segment and the final end."""
    draw = ImageDraw.Draw(img)
    s = spec.scale
    halo = pal.ink(st.HALO)
    order = sorted(outcome.segments, key=lambda i: (i == 0, i))
    for ball_id in order:
        points: list[Point] = []
        for seg in outcome.segments[ball_id]:
            end = segment_end(seg)
            if end == seg.pos:
                continue
            if not points or points[-1] != seg.pos:
                points.append(seg.pos)
            points.append(end)
        pts = [spec.to_px(*p) for p in points]
        if len(pts) < 2:
            continue
        draw.line(pts, fill=halo, width=round(6 * s), joint="curve")
        draw.line(pts, fill=pal.ink(st.ball_colour(ball_id)), width=round(3 * s), joint="curve")


def draw_markers(img: Image.Image, spec: CanvasSpec, pal: Palette, outcome: Outcome) -> None:
    """Mark every contact and pocketing (drawn last, above the balls, so none is hidden)."""
    draw = ImageDraw.Draw(img)
    s, halo = spec.scale, pal.ink(st.HALO)
    for event in outcome.events:
        if not event.positions:
            continue
        if event.kind == "ball" and len(event.positions) >= 2:
            (ax, ay), (bx, by) = event.positions[:2]
            x, y = spec.to_px((ax + bx) / 2, (ay + by) / 2)
            r = 7 * s
            ring = (x - r - 2, y - r - 2, x + r + 2, y + r + 2)
            draw.ellipse(ring, outline=halo, width=round(5 * s))
            draw.ellipse(
                (x - r, y - r, x + r, y + r), outline=pal.ink(st.MARK_BALL), width=round(3 * s)
            )
        elif event.kind == "wall":
            x, y = spec.to_px(*event.positions[0])
            wall_diamond(img, (x, y), 7 * s, pal.ink(st.MARK_WALL), halo, max(1, round(2 * s)))
        elif event.kind == "pocket":
            x, y = spec.to_px(*event.positions[0])
            r = 8 * s
            for ink, width in ((halo, 6), (pal.ink(st.MARK_POCKET), 3)):
                for dx in (-r, r):
                    draw.line(((x - dx, y - r), (x + dx, y + r)), fill=ink, width=round(width * s))


def wall_diamond(
    img: Image.Image, centre: Point, r: float, fill: int, outline: int, width: int
) -> None:
    """The wall marker: a diamond of half-diagonal ``r`` at ``centre`` (pixels), outlined
    ``width`` wide inside its edge.

    Drawn on a crop around it and pasted back: Pillow outlines a polygon more than a pixel wide
    through a mask as large as the image drawn on (a megabyte here), and the crop's is small.
    The crop's pixels are the canvas's: Pillow rounds polygon corners to whole pixels, and the
    crop moves them by whole pixels.
    """
    x, y = centre
    pad = 2 * width + 2
    box = (
        max(0, math.floor(x - r) - pad),
        max(0, math.floor(y - r) - pad),
        min(img.width, math.ceil(x + r) + pad + 1),
        min(img.height, math.ceil(y + r) + pad + 1),
    )
    if box[0] >= box[2] or box[1] >= box[3]:
        return
    crop = img.crop(box)
    dx, dy = box[0], box[1]
    diamond = [
        (x - dx, y - r - dy),
        (x + r - dx, y - dy),
        (x - dx, y + r - dy),
        (x - r - dx, y - dy),
    ]
    ImageDraw.Draw(crop).polygon(diamond, fill=fill, outline=outline, width=width)
    img.paste(crop, box[:2])


PLAIN_PX_PER_M = 400.0
PLAIN_MARGIN = 40


def scene_picture(dataset: Path, folder: Path, scene: Scene) -> ScenePicture:
    """The scene's own image when its geometry is known, else a plain table."""
    for name in ("trajectory.png", "init.png"):
        path = folder / name
        if path.is_file():
            with Image.open(path) as img:
                image = img.convert("RGB")
            picture = _mapped(dataset, image)
            if picture is not None:
                return picture
    return plain_table(scene)


def _mapped(dataset: Path, image: Image.Image) -> ScenePicture | None:
    """The mapping of the dataset's images, if ``dataset.json`` records it and the size fits."""
    try:
        config = json.loads((dataset / MANIFEST).read_text(encoding="utf-8"))["config"]
        im, table = config.get("image", {}), config.get("table", {})
        ppm = float(im.get("px_per_m", 600.0))
        left, right = int(im.get("margin_left", 116)), int(im.get("margin_right", 48))
        top, bottom = int(im.get("margin_top", 84)), int(im.get("margin_bottom", 96))
        width, height = float(table.get("width", 2.0)), float(table.get("height", 1.0))
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None
    size = (left + round(width * ppm) + right, top + round(height * ppm) + bottom)
    return ScenePicture(image, left, top, ppm, height) if image.size == size else None


def plain_table(scene: Scene) -> ScenePicture:
    """Cloth, pockets and numbered balls at their starting places."""
    width, height = scene.table.width, scene.table.height
    ppm, margin = PLAIN_PX_PER_M, PLAIN_MARGIN
    size = (round(width * ppm) + 2 * margin, round(height * ppm) + 2 * margin)
    image = Image.new("RGB", size, (245, 245, 240))
    picture = ScenePicture(image, margin, margin, ppm, height)
    draw = ImageDraw.Draw(image)
    draw.rectangle((margin, margin, size[0] - margin, size[1] - margin), fill=(30, 110, 60))
    r_pocket = scene.pockets.radius * ppm
    for cx, cy in scene.pockets.centers:
        px, py = picture.to_px(cx, cy)
        box = (px - r_pocket, py - r_pocket, px + r_pocket, py + r_pocket)
        draw.ellipse(box, fill=(20, 20, 20))
    r = scene.physics.ball_radius * ppm
    for ball in scene.balls:
        px, py = picture.to_px(*ball.pos)
        draw.ellipse((px - r, py - r, px + r, py + r), fill=(250, 250, 250), outline=(0, 0, 0))
        draw.text(
            (px, py), str(ball.id), fill=(0, 0, 0), anchor="mm", font=gallery_font(int(r * 1.2))
        )
    return picture
