"""Ball centres and ids by template matching against the renderer's own ball sprites.

Each id has its own fill colour (:func:`~bpb_tasks.billiards.render_style.ball_colour`), drawn
flat between the dark rim and the white badge. The template of ball ``i`` is the set of pixels of
the renderer's own sprite that carry that colour as the canvas's palette draws it; the image's
pixels of that colour are matched against it at every offset within a few pixels of their median
(a dozen when that does not fit well), and the offset covering the most of them is where the
renderer pasted the sprite, at a whole pixel (the speed label pasted over a ball hides part of
it, not the rest). Ids sharing a colour (more than 8 balls) cannot be told apart: that is a
perception failure, named.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import NDArray

from bpb_tasks.billiards import render_style as st
from bpb_tasks.billiards.render_canvas import CanvasSpec
from bpb_tasks.billiards.render_palette import stamp
from bpb_tasks.billiards.vision.frame import Keys, image_keys, shown
from bpb_tasks.billiards.vision.prompt_facts import PerceptionFailed

SEARCH = 12  # pixels around the median of a colour's pixels searched for the sprite
NEAR = 3  # searched first: the median is that close unless the speed label hides part
MIN_COVER = 0.05  # share of a template the best match must cover (the speed label may hide most)


@functools.cache
def template(spec: CanvasSpec, ball_id: int) -> tuple[NDArray[np.intp], NDArray[np.intp], int]:
    """Rows and columns (from the sprite's top-left) of the sprite's flat-colour pixels, and the
    sprite's half side (the paste offset of its centre)."""
    sprite, mask = stamp(spec, ball_id)
    keys = image_keys_of(sprite.convert("RGB").tobytes(), sprite.size)
    flat = (keys == fill_colour(spec, ball_id)) & (np.asarray(mask) > 0)
    rows, cols = np.nonzero(flat)
    return rows, cols, sprite.width // 2


@functools.cache
def fill_colour(spec: CanvasSpec, ball_id: int) -> int:
    """The colour key the renderer fills ball ``ball_id`` with on this canvas: the commonest
    sprite colour near the flat one (the palette may move it by a few levels)."""
    sprite, mask = stamp(spec, ball_id)
    keys = image_keys_of(sprite.convert("RGB").tobytes(), sprite.size)[np.asarray(mask) > 0]
    colours, counts = np.unique(keys, return_counts=True)
    channels = np.stack([(colours >> s) & 255 for s in (16, 8, 0)], axis=1)
    close = np.abs(channels - np.array(st.ball_colour(ball_id))).sum(axis=1) <= 24
    if not close.any():
        return int(colours[np.argmax(counts)])
    return int(colours[close][np.argmax(counts[close])])


def image_keys_of(raw: bytes, size: tuple[int, int]) -> Keys:
    """Colour keys of raw RGB bytes of ``size``."""
    rgb = np.frombuffer(raw, dtype=np.uint8).reshape(size[1], size[0], 3).astype(np.int32)
    return (rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]


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
