"""The balls read from the image: every centre and id, and the cue ball's velocity.

Ball centres and ids come from template matching against the renderer's own ball sprites. Each
id has its own fill colour (:func:`~bpb_tasks.billiards.render.canvas.ball_colour`), drawn flat
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

import numpy as np
from numpy.typing import NDArray

from bpb_tasks.billiards.render import canvas as st
from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.render.images import speed_note
from bpb_tasks.billiards.render.palette import header_y, stamp, text_patch
from bpb_tasks.billiards.vision.frame import (
    Keys,
    PerceptionFailed,
    image_keys,
    image_keys_of,
    shown,
)

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
