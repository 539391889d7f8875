"""The cue ball's velocity: the speed printed in the header, the direction of the arrow.

The header note (:func:`~bpb_tasks.billiards.render.speed_note`) is right-aligned in the header
line. Its digits are read one at a time: each candidate note is drawn with the renderer's own
font and text patch and compared pixel by pixel with the image, keeping the digit that differs
least (two passes). The arrow is the only thing drawn in the arrow colour; its direction is the
principal axis of those pixels, pointing away from the cue ball.
"""

from __future__ import annotations

import math

import numpy as np

from bpb_tasks.billiards import render_style as st
from bpb_tasks.billiards.render import speed_note
from bpb_tasks.billiards.render_canvas import CanvasSpec
from bpb_tasks.billiards.render_palette import header_y, text_patch
from bpb_tasks.billiards.vision.balls import image_keys_of
from bpb_tasks.billiards.vision.frame import Keys, shown
from bpb_tasks.billiards.vision.prompt_facts import PerceptionFailed

DIGITS = "0123456789"
MAX_MISMATCH = 0.02  # share of the note's pixels that may differ from the best reading


def _note_keys(spec: CanvasSpec, text: str) -> Keys:
    patch = text_patch(spec, text, st.font(round(16 * spec.scale)), st.MUTED, st.PAGE)
    rgb = patch.convert("RGB")
    return image_keys_of(rgb.tobytes(), rgb.size)


def _mismatch(keys: Keys, spec: CanvasSpec, text: str, span: int) -> int:
    """Pixels that differ between the image's header strip and ``text`` drawn there."""
    note = _note_keys(spec, text)
    h, w = note.shape
    right = keys.shape[1] - spec.right
    top = round(header_y(spec) - h / 2)
    if top < 0 or right - span < 0:
        return keys.size
    strip = keys[top : top + h, right - span : right]
    drawn = np.full(strip.shape, shown(spec, st.PAGE), dtype=np.int32)
    drawn[:, span - min(w, span) :] = note[:, w - min(w, span) :]
    return int((strip != drawn).sum())


def _decode(keys: Keys, spec: CanvasSpec, int_digits: int, span: int) -> tuple[int, str]:
    slots = ["0"] * (int_digits + 3)

    def text() -> str:
        return speed_note(float("".join(slots[:int_digits]) + "." + "".join(slots[int_digits:])))

    best = _mismatch(keys, spec, text(), span)
    for _ in range(2):
        for i in range(len(slots)):
            for digit in DIGITS:
                old, slots[i] = slots[i], digit
                score = _mismatch(keys, spec, text(), span)
                if score < best:
                    best = score
                else:
                    slots[i] = old
    return best, text()


def read_speed(keys: Keys, spec: CanvasSpec) -> float:
    """The cue speed (m/s) printed in the header, to its three decimals.

    Raises:
        PerceptionFailed: No reading matches the header well enough.
    """
    span = _note_keys(spec, speed_note(100.0)).shape[1] + 4
    score, text = min(_decode(keys, spec, n, span) for n in (1, 2))
    if score > MAX_MISMATCH * span * _note_keys(spec, text).shape[0]:
        raise PerceptionFailed(f"the cue speed note cannot be read ({score} pixels differ)")
    return float(text.split(" speed ")[1].split()[0])


def read_direction(keys: Keys, spec: CanvasSpec, cue_px: tuple[float, float]) -> float:
    """Angle (radians, table convention: counter-clockwise from +x) of the cue arrow.

    Raises:
        PerceptionFailed: No arrow is drawn, or too little of it is visible.
    """
    points = np.argwhere(keys == shown(spec, st.ARROW)).astype(float)
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
    away = centre - np.array([cue_px[1], cue_px[0]])
    if away @ axis < 0:
        axis = -axis
    return math.atan2(-axis[0], axis[1])  # rows grow downward, y upward
