"""Ball centres and ids by template matching against the renderer's own ball sprites.

Each id has its own fill colour (:func:`~bpb_tasks.billiards.render_style.ball_colour`), drawn
flat between the dark rim and the white badge. The template of ball ``i`` is the set of sprite
pixels that carry exactly that colour; the image's pixels of that colour are matched against it
at every offset near their median, and the offset covering the most of them is where the
renderer pasted the sprite (the speed label pasted over a ball hides part of it, not the rest).
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
MIN_COVER = 0.5  # share of a template the best match must cover


@functools.cache
def template(spec: CanvasSpec, ball_id: int) -> tuple[NDArray[np.intp], NDArray[np.intp], int]:
    """Rows and columns (from the sprite's top-left) of the sprite's flat-colour pixels, and the
    sprite's half side (the paste offset of its centre)."""
    sprite, mask = stamp(spec, ball_id)
    keys = image_keys_of(sprite.convert("RGB").tobytes(), sprite.size)
    flat = (keys == shown(spec, st.ball_colour(ball_id))) & (np.asarray(mask) > 0)
    rows, cols = np.nonzero(flat)
    return rows, cols, sprite.width // 2


def image_keys_of(raw: bytes, size: tuple[int, int]) -> Keys:
    """Colour keys of raw RGB bytes of ``size``."""
    rgb = np.frombuffer(raw, dtype=np.uint8).reshape(size[1], size[0], 3).astype(np.int32)
    return (rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]


def find_ball(keys: Keys, spec: CanvasSpec, ball_id: int) -> tuple[float, float]:
    """Pixel centre of ball ``ball_id`` (the sprite's centre pixel).

    Raises:
        PerceptionFailed: The colour is absent or no offset fits the sprite well enough.
    """
    hits = keys == shown(spec, st.ball_colour(ball_id))
    points = np.argwhere(hits)
    if len(points) == 0:
        raise PerceptionFailed(f"ball {ball_id} not found in the image")
    rows, cols, half = template(spec, ball_id)
    my, mx = np.median(points, axis=0).astype(int) - half
    padded = np.pad(hits, SEARCH + 2 * half + 2)
    shift = SEARCH + 2 * half + 2
    best, where = -1, [(0, 0)]
    for dy in range(-SEARCH, SEARCH + 1):
        r = rows + my + dy + shift
        for dx in range(-SEARCH, SEARCH + 1):
            cover = int(padded[r, cols + mx + dx + shift].sum())
            if cover > best:
                best, where = cover, [(dy, dx)]
            elif cover == best:
                where.append((dy, dx))
    if best < MIN_COVER * len(rows):
        raise PerceptionFailed(
            f"ball {ball_id}: its colour does not form a whole ball (best cover {best} of "
            f"{len(rows)} pixels)"
        )
    dy, dx = np.mean(np.array(where, dtype=float), axis=0)
    return float(mx + dx + half), float(my + dy + half)


def find_balls(
    png: bytes | Keys, spec: CanvasSpec, ids: tuple[int, ...]
) -> dict[int, tuple[float, float]]:
    """Pixel centres of the balls ``ids``.

    Raises:
        PerceptionFailed: Two ids share a colour, or a ball is missing.
    """
    colours = [shown(spec, st.ball_colour(i)) for i in ids]
    if len(set(colours)) != len(colours):
        raise PerceptionFailed(f"{len(ids)} balls but only {len(set(colours))} ball colours")
    keys = image_keys(png) if isinstance(png, bytes) else png
    return {i: find_ball(keys, spec, i) for i in ids}
