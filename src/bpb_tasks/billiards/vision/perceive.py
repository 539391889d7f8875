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

The balls are read from the image: every centre and id, and the cue ball's velocity. Ball
centres and ids come from template matching against the renderer's own ball sprites. Each id
has its own fill colour (:func:`~bpb_tasks.billiards.render.canvas.ball_colour`), drawn flat
between the dark rim and the white badge. The template of ball ``i`` is the set of pixels of the
renderer's own sprite that carry that colour as the canvas's palette draws it; the image's pixels
of that colour are matched against it at every offset within a few pixels of their median (a
dozen when that does not fit well), and the offset covering the most of them is where the
renderer pasted the sprite, at a whole pixel (the speed label pasted over a ball hides part of
it, not the rest). Ids sharing a colour (more than 8 balls) cannot be told apart: that is a
perception failure, named.

The cue ball's speed is the one printed in the header, its direction the arrow's. The header note
(:func:`~bpb_tasks.billiards.render.images.speed_note`) is right-aligned in the header line. Its
digits are read one place at a time: the note is drawn with the renderer's own font and text patch
with each digit in that place and compared with the image over that place's columns, keeping the
digit that differs least; the whole reading must then match the note. The arrow is the only thing
drawn in the arrow colour; its direction weighs the principal axis of those pixels against
the line from the cue ball's centre to their centroid (:func:`_combined`). The notes of every
digit in every place are drawn once per canvas (cached), so reading a note costs a few array
comparisons.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bpb_core.errors import BpbError
from bpb_tasks.billiards.render import canvas as st
from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.render.images import speed_note
from bpb_tasks.billiards.render.palette import header_y, stamp, text_patch
from bpb_tasks.billiards.scene.model import Ball, Scene
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.billiards.truth.outcome import CUE_ID
from bpb_tasks.billiards.vision.frame import (
    Keys,
    PerceptionFailed,
    PromptFacts,
    canvas_of,
    find_frame,
    image_keys,
    image_keys_of,
    read_prompt,
    shown,
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


SEARCH = 12  # pixels around the median of a colour's pixels searched for the sprite
NEAR = 3  # searched first: the median is that close unless the speed label hides part
MIN_COVER = 0.05  # share of a template the best match must cover (the speed label may hide most)


@functools.cache
def template(spec: CanvasSpec, ball_id: int) -> tuple[NDArray[np.intp], NDArray[np.intp], int]:
    """Rows and columns (from the sprite's top-left) of the sprite's flat-colour pixels, and the
    sprite's half side (the paste offset of its centre)."""
    sprite, mask = stamp(spec, ball_id)
    keys = image_keys_of(sprite)
    flat = (keys == fill_colour(spec, ball_id)) & (np.asarray(mask) > 0)
    rows, cols = np.nonzero(flat)
    return rows, cols, sprite.width // 2


@functools.cache
def fill_colour(spec: CanvasSpec, ball_id: int) -> int:
    """The colour key the renderer fills ball ``ball_id`` with on this canvas: the commonest
    sprite colour near the flat one (the palette may move it by a few levels)."""
    sprite, mask = stamp(spec, ball_id)
    keys = image_keys_of(sprite)[np.asarray(mask) > 0]
    colours, counts = np.unique(keys, return_counts=True)
    channels = np.stack([(colours >> s) & 255 for s in (16, 8, 0)], axis=1)
    close = np.abs(channels - np.array(st.ball_colour(ball_id))).sum(axis=1) <= 24
    if not close.any():
        return int(colours[np.argmax(counts)])
    return int(colours[close][np.argmax(counts[close])])


def find_ball(keys: Keys, spec: CanvasSpec, ball_id: int, colour: int) -> tuple[float, float]:
    """Pixel centre of ball ``ball_id`` (the sprite's centre pixel).

    Raises:
        PerceptionFailed: The colour is absent or no offset fits the sprite well enough.
    """
    hits = keys == colour
    points = np.argwhere(hits)
    if len(points) == 0:
        raise PerceptionFailed(f"ball {ball_id} not found in the image")
    rows, cols, half = template(spec, ball_id)
    my, mx = np.median(points, axis=0).astype(int) - half
    window = _window(hits, my - SEARCH, mx - SEARCH, 2 * (half + SEARCH) + 1)
    best, where = _best_offsets(window, rows + SEARCH, cols + SEARCH, NEAR)
    inside = not (np.abs(np.array(where)) == NEAR).any()
    if best < len(rows) and not (inside and best >= 0.9 * len(rows)):
        best, where = _best_offsets(window, rows + SEARCH, cols + SEARCH, SEARCH)
    if best < MIN_COVER * len(rows):
        raise PerceptionFailed(
            f"ball {ball_id}: its colour does not form a whole ball (best cover {best} of "
            f"{len(rows)} pixels)"
        )
    dy, dx = np.mean(np.array(where, dtype=float), axis=0)
    return float(mx + dx + half), float(my + dy + half)


def _window(hits: NDArray[np.bool_], top: int, left: int, size: int) -> NDArray[np.bool_]:
    """The ``size`` square of ``hits`` at (``top``, ``left``), False beyond the image."""
    out = np.zeros((size, size), dtype=bool)
    r0, c0 = max(top, 0), max(left, 0)
    r1, c1 = min(top + size, hits.shape[0]), min(left + size, hits.shape[1])
    if r0 < r1 and c0 < c1:
        out[r0 - top : r1 - top, c0 - left : c1 - left] = hits[r0:r1, c0:c1]
    return out


def _best_offsets(
    hits: NDArray[np.bool_], rows: NDArray[np.intp], cols: NDArray[np.intp], reach: int
) -> tuple[int, list[tuple[int, int]]]:
    """The largest number of template pixels on ``hits`` over offsets up to ``reach``, and the
    offsets that reach it."""
    best, where = -1, [(0, 0)]
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            cover = int(hits[rows + dy, cols + dx].sum())
            if cover > best:
                best, where = cover, [(dy, dx)]
            elif cover == best:
                where.append((dy, dx))
    return best, where


def find_balls(
    png: bytes | Keys, spec: CanvasSpec, ids: tuple[int, ...]
) -> dict[int, tuple[float, float]]:
    """Pixel centres of the balls ``ids``.

    Raises:
        PerceptionFailed: Two ids share a colour, or a ball is missing.
    """
    keys = image_keys(png) if isinstance(png, bytes) else png
    present = set(np.unique(keys).tolist())
    colours = [
        c if (c := fill_colour(spec, i)) in present else shown(keys, st.ball_colour(i)) for i in ids
    ]
    found = [c for c in colours if c >= 0]
    if len(set(found)) != len(found):
        raise PerceptionFailed(f"{len(ids)} balls but only {len(set(colours))} ball colours")
    return {i: find_ball(keys, spec, i, c) for i, c in zip(ids, colours, strict=True)}


DIGITS = "0123456789"
MAX_MISMATCH = 0.02  # share of the note's pixels that may differ from the best reading


@functools.lru_cache(maxsize=64)
def _note_keys(spec: CanvasSpec, text: str) -> Keys:
    return image_keys_of(text_patch(spec, text, st.font(round(16 * spec.scale)), st.MUTED, st.PAGE))


def _reading(int_digits: int, digits: list[str]) -> str:
    return speed_note(float("".join(digits[:int_digits]) + "." + "".join(digits[int_digits:])))


@functools.lru_cache(maxsize=8)
def _slots(spec: CanvasSpec, int_digits: int) -> tuple[tuple[Keys, NDArray[np.intp]], ...]:
    """Per digit slot of a note with ``int_digits`` digits before the point: the note drawn
    with each digit 0-9 in that slot (zeros elsewhere) and the columns where they differ.
    Digits have equal widths in the renderer's font, so the columns are the same for every
    speed; a leading zero is drawn as 1 so that the note keeps its digits."""
    slots = []
    for slot in range(int_digits + 3):
        drawn = []
        for digit in DIGITS:
            digits = ["1" if i == 0 and int_digits > 1 else "0" for i in range(int_digits + 3)]
            digits[slot] = digit if not (slot == 0 and int_digits > 1 and digit == "0") else "1"
            drawn.append(_note_keys(spec, _reading(int_digits, digits)))
        stack = np.stack(drawn)
        columns = np.flatnonzero((stack != stack[:1]).any(axis=(0, 1)))
        slots.append((stack, columns))
    return tuple(slots)


def _strip(keys: Keys, spec: CanvasSpec, shape: tuple[int, ...]) -> Keys | None:
    h, w = shape
    right = keys.shape[1] - spec.right
    top = round(header_y(spec) - h / 2)
    if top < 0 or right - w < 0 or top + h > keys.shape[0]:
        return None
    return keys[top : top + h, right - w : right]


def _decode(keys: Keys, spec: CanvasSpec, int_digits: int) -> tuple[int, str]:
    """Mismatching pixels of the best reading with ``int_digits`` digits before the point."""
    slots = _slots(spec, int_digits)
    strip = _strip(keys, spec, slots[0][0].shape[1:])
    if strip is None:
        return keys.size, ""
    digits = []
    for stack, columns in slots:
        wrong = (stack[:, :, columns] != strip[None, :, columns]).sum(axis=(1, 2))
        digits.append(DIGITS[int(np.argmin(wrong))])
    text = _reading(int_digits, digits)
    note = _note_keys(spec, text)
    if note.shape != strip.shape:
        return keys.size, text
    return int((note != strip).sum()), text


def read_speed(keys: Keys, spec: CanvasSpec) -> float:
    """The cue speed (m/s) printed in the header, to its three decimals.

    Raises:
        PerceptionFailed: No reading matches the header well enough.
    """
    score, text = min(_decode(keys, spec, n) for n in (1, 2))
    if not text or score > MAX_MISMATCH * _note_keys(spec, text).size:
        raise PerceptionFailed(f"the cue speed note cannot be read ({score} pixels differ)")
    return float(text.split(" speed ")[1].split()[0])


def read_direction(keys: Keys, spec: CanvasSpec, cue_px: tuple[float, float]) -> float:
    """Angle (radians, table convention: counter-clockwise from +x) of the cue arrow.

    Raises:
        PerceptionFailed: No arrow is drawn, or too little of it is visible.
    """
    points = np.argwhere(keys == shown(keys, st.ARROW)).astype(float)
    if len(points) < 20:
        raise PerceptionFailed("no cue arrow found")
    for _ in range(2):  # refit without pixels far from the first axis
        centre = points.mean(axis=0)
        _, _, axes = np.linalg.svd(points - centre, full_matrices=False)
        axis = axes[0]
        off = np.abs((points - centre) @ np.array([-axis[1], axis[0]]))
        kept = points[off <= 6]
        if len(kept) >= 20:
            points = kept
    away = points.mean(axis=0) - np.array([cue_px[1], cue_px[0]])
    if away @ axis < 0:
        axis = -axis
    reach = float(((points - np.array([cue_px[1], cue_px[0]])) @ axis).max())  # centre to tip
    return _combined(axis, away, reach, spec)


def _combined(
    axis: NDArray[np.float64], away: NDArray[np.float64], length: float, spec: CanvasSpec
) -> float:
    """The arrow's direction from two readings weighted by how well each holds at this length:
    the pixels' principal axis (good on a long arrow, wobbly on a short one, where the head is
    most of it) and the line from the cue ball's centre to the arrow's centroid (the arrow is
    symmetric about it; off by the centre's sub-pixel error over that distance).

    The error models are fitted on 1,000 generated scenes (medians: axis 0.27 degrees and centre
    line 0.42 degrees at 110 px from the centre to the tip at 600 px/m, falling as length^-1.6
    and length^-0.6); weighting by them cut the median direction error from 0.20 (axis) and 0.34
    (centre line) to 0.14 degrees."""
    size = max(length / spec.scale, 1.0) / 110
    w_axis = (math.pow(size, 1.6) / 0.27) ** 2
    w_centre = (math.pow(size, 0.6) / 0.42) ** 2
    a = math.atan2(float(-axis[0]), float(axis[1]))  # rows grow downward, y upward
    c = math.atan2(float(-away[0]), float(away[1]))
    gap = (c - a + math.pi) % (2 * math.pi) - math.pi
    return a + gap * w_centre / (w_axis + w_centre)
