"""Paths and event markers of the trajectory image, drawn from an :class:`Outcome`.

Each :class:`~bpb_tasks.billiards.outcome.Segment` is straight (friction acts along the
velocity), so a path is a polyline through the segment end points. Ball-ball contacts are marked
by a red ring at the contact point, wall contacts by a blue diamond at the centre, pocketings by
a white cross.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from PIL import Image, ImageDraw

from bpb_tasks.billiards import render_style as st
from bpb_tasks.billiards.outcome import Event, Outcome, Segment
from bpb_tasks.billiards.render_canvas import CanvasSpec

if TYPE_CHECKING:
    from bpb_tasks.billiards.render_palette import Palette

Point = tuple[float, float]


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


def path_points(segments: tuple[Segment, ...]) -> list[Point]:
    """Table points of a ball's path: the start of each moving segment and the final end."""
    points: list[Point] = []
    for seg in segments:
        end = segment_end(seg)
        if end == seg.pos:
            continue
        if not points or points[-1] != seg.pos:
            points.append(seg.pos)
        points.append(end)
    return points


def draw_trajectories(img: Image.Image, spec: CanvasSpec, pal: Palette, outcome: Outcome) -> None:
    """Draw every moving ball's path (cue ball last, on top), then the event markers."""
    draw_paths(img, spec, pal, outcome)
    draw_markers(img, spec, pal, outcome)


def draw_paths(img: Image.Image, spec: CanvasSpec, pal: Palette, outcome: Outcome) -> None:
    """Draw every moving ball's path, the cue ball's last (on top)."""
    draw = ImageDraw.Draw(img)
    s = spec.scale
    halo = pal.ink(st.HALO)
    order = sorted(outcome.segments, key=lambda i: (i == 0, i))
    for ball_id in order:
        pts = [spec.to_px(*p) for p in path_points(outcome.segments[ball_id])]
        if len(pts) < 2:
            continue
        draw.line(pts, fill=halo, width=round(6 * s), joint="curve")
        draw.line(pts, fill=pal.ink(st.ball_colour(ball_id)), width=round(3 * s), joint="curve")


def draw_markers(img: Image.Image, spec: CanvasSpec, pal: Palette, outcome: Outcome) -> None:
    """Mark every contact and pocketing (drawn last, above the balls, so none is hidden)."""
    draw = ImageDraw.Draw(img)
    for event in outcome.events:
        _mark(img, draw, spec, pal, event)


def _mark(
    img: Image.Image, draw: ImageDraw.ImageDraw, spec: CanvasSpec, pal: Palette, event: Event
) -> None:
    if not event.positions:
        return
    s, halo = spec.scale, pal.ink(st.HALO)
    if event.kind == "ball" and len(event.positions) >= 2:
        (ax, ay), (bx, by) = event.positions[:2]
        x, y = spec.to_px((ax + bx) / 2, (ay + by) / 2)
        r = 7 * s
        draw.ellipse((x - r - 2, y - r - 2, x + r + 2, y + r + 2), outline=halo, width=round(5 * s))
        draw.ellipse(
            (x - r, y - r, x + r, y + r), outline=pal.ink(st.MARK_BALL), width=round(3 * s)
        )
    elif event.kind == "wall":
        x, y = spec.to_px(*event.positions[0])
        r = 7 * s
        width = max(1, round(2 * s))
        wall_diamond(img, (x, y), r, pal.ink(st.MARK_WALL), halo, width)
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
    through a mask as large as the image drawn on (a megabyte here, ~30 us a marker, against
    ~5 on the crop). The crop's pixels are the canvas's: Pillow rounds polygon corners to whole
    pixels, and the crop moves them by whole pixels.
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
