"""What is read before the balls: the facts the common prompt states in words, and the table
frame read from the image's axes.

The prompt states the horizon, table, ball ids, radius, friction, restitution and pockets (see
:mod:`bpb_tasks.questions.question`, whose wording :func:`read_prompt` reads). The renderer draws a
one-pixel x axis under the table and a y axis left of it, with a tick every
:data:`~bpb_tasks.billiards.render.canvas.TICK_MINOR` metres starting at 0. The longest ink row
and column are the axes; the ticks next to them give the origin and the scale (where x = 0 and
y = 0 are and how many pixels a metre is), and the canvas the renderer drew on follows from them
and the prompt's table and pockets.
"""

from __future__ import annotations

import io
import math
import re
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from PIL import Image

from bpb_tasks.billiards.render import canvas as st
from bpb_tasks.billiards.render.canvas import TICK_MINOR, CanvasSpec
from bpb_tasks.billiards.scene.model import Physics, Pockets, Table

_NUM = r"([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)"
Keys = NDArray[np.int32]
Frame1D = tuple[NDArray[np.float64], float]
GAP = 60  # pixels of an axis line the cue arrow may hide


class PerceptionFailed(ValueError):
    """The image or the prompt could not be read; the message says what was missing."""


@dataclass(frozen=True)
class PromptFacts:
    """What the prompt says about the scene besides the picture."""

    scene_id: str
    horizon: float
    table: Table
    physics: Physics
    pockets: Pockets
    ids: tuple[int, ...]


def _find(pattern: str, text: str, what: str) -> re.Match[str]:
    match = re.search(pattern, text)
    if match is None:
        raise PerceptionFailed(f"the prompt does not state the {what}")
    return match


def _pockets(text: str) -> Pockets:
    if "Pockets: none" in text:
        return Pockets(radius=0.0, centers=[])
    stated = rf"Pockets: \d+ pockets of radius {_NUM} m centred at (.*?)\. A ball"
    match = _find(stated, text, "pockets")
    centres = [(float(x), float(y)) for x, y in re.findall(rf"\({_NUM}, {_NUM}\)", match.group(2))]
    return Pockets(radius=float(match.group(1)), centers=centres)


def read_prompt(text: str) -> PromptFacts:
    """The scene's stated facts.

    Raises:
        PerceptionFailed: A fact is missing from ``text`` (names it).
    """
    scene_id = _find(r"\(scene ([^)\s]+)\)", text, "scene id").group(1)
    horizon = float(_find(rf"until t = {_NUM} s", text, "horizon").group(1))
    size = _find(rf"Table: {_NUM} m along x by {_NUM} m along y", text, "table size")
    ids = _find(r"Balls: (\d+) balls with ids (\d+)\.\.(\d+)", text, "ball ids")
    radius = float(_find(rf"radius R = {_NUM} m", text, "ball radius").group(1))
    friction = _find(rf"mu = {_NUM} and g = {_NUM} m/s", text, "friction")
    stated = re.search(rf"wall collisions are with restitution {_NUM}", text)
    restitution = float(stated.group(1)) if stated else 1.0
    return PromptFacts(
        scene_id,
        horizon,
        Table(width=float(size.group(1)), height=float(size.group(2))),
        Physics(
            ball_radius=radius,
            mu=float(friction.group(1)),
            g=float(friction.group(2)),
            wall_restitution=restitution,
        ),
        _pockets(text),
        tuple(range(int(ids.group(2)), int(ids.group(3)) + 1)),
    )


def near(keys: Keys, rgb: st.RGB, tolerance: int = 6) -> NDArray[np.bool_]:
    """Where ``keys`` is within ``tolerance`` of ``rgb`` in every channel (the palette the
    images are drawn in moves some flat colours by a few levels)."""
    out = np.ones(keys.shape, dtype=bool)
    for shift, level in zip((16, 8, 0), rgb, strict=True):
        out &= np.abs(((keys >> shift) & 255) - level) <= tolerance
    return out


def shown(keys: Keys, rgb: st.RGB, within: int = 12) -> int:
    """The colour of ``keys`` nearest to ``rgb``: what a flat colour became in the palette the
    image was drawn in (it moves some colours by a few levels); -1 when none is ``within``
    that distance (sum over channels)."""
    colours = np.unique(keys)
    channels = np.stack([(colours >> s) & 255 for s in (16, 8, 0)], axis=1)
    distance = np.abs(channels - np.array(rgb)).sum(axis=1)
    nearest = int(np.argmin(distance))
    return int(colours[nearest]) if distance[nearest] <= within else -1


def image_keys(png: bytes) -> Keys:
    """The image as an (height, width) array of colour keys.

    Raises:
        PerceptionFailed: The bytes are not an image Pillow can read.
    """
    try:
        with Image.open(io.BytesIO(png)) as img:
            rgb = img.convert("RGB")
    except (OSError, ValueError) as exc:
        raise PerceptionFailed(f"the image cannot be read: {exc}") from None
    return image_keys_of(rgb)


def image_keys_of(image: Image.Image) -> Keys:
    """Colour keys of a Pillow image, read as RGB."""
    raw, (width, height) = image.convert("RGB").tobytes(), image.size
    rgb = np.frombuffer(raw, dtype=np.uint8).reshape(height, width, 3).astype(np.int32)
    return (rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]


@dataclass(frozen=True)
class Frame:
    """Pixel position of the table origin and the scale.

    Attributes:
        x0: Column of x = 0.
        y0: Row of y = 0.
        ppm: Pixels per metre.
    """

    x0: float
    y0: float
    ppm: float

    def to_table(self, px: float, py: float) -> tuple[float, float]:
        """Table coordinates (m) of pixel ``(px, py)``."""
        return (px - self.x0) / self.ppm, (self.y0 - py) / self.ppm


def _extent(line: NDArray[np.bool_]) -> tuple[int, int]:
    """First and last index of the longest stretch of True in ``line``, bridging gaps of up to
    :data:`GAP` (where the cue arrow crosses the axis)."""
    found = np.flatnonzero(line)
    breaks = np.flatnonzero(np.diff(found) > GAP)
    starts = np.concatenate(([0], breaks + 1))
    ends = np.concatenate((breaks, [len(found) - 1]))
    longest = int(np.argmax(found[ends] - found[starts]))
    return int(found[starts[longest]]), int(found[ends[longest]])


def _tick_marks(beside: NDArray[np.bool_], ends: tuple[int, int]) -> NDArray[np.intp]:
    """Positions of one-pixel ink marks beside the axis within its extent (text is thicker)."""
    inside = np.zeros_like(beside)
    inside[ends[0] : ends[1] + 1] = beside[ends[0] : ends[1] + 1]
    padded = np.concatenate(([False], inside, [False]))
    alone = inside & ~padded[:-2] & ~padded[2:]
    return np.flatnonzero(alone)


def _fit_ticks(ticks: NDArray[np.intp], ends: tuple[int, int], length: float, axis: str) -> Frame1D:
    """Tick numbers (0 at the zero end) and spacing of the visible ``ticks`` (pixels from the
    zero end) of an axis ``length`` metres long: the cue arrow may hide some, so they are
    numbered from whichever end of the axis line fits (the far end only when it has a tick)."""
    count = math.floor(length / TICK_MINOR + 1e-9) + 1
    anchors = [(ends[0], 0)]
    if abs(length / TICK_MINOR - (count - 1)) < 1e-9:
        anchors.append((ends[1], count - 1))
    if len(ticks) < max(3, count // 2):
        raise PerceptionFailed(f"the {axis} axis shows {len(ticks)} ticks, expected {count}")
    diffs = np.diff(ticks).astype(float)
    step = float(np.median(diffs[diffs <= 1.5 * diffs.min()]))
    for anchor, sign in anchors:
        index = np.rint((ticks - anchor) / step) + sign
        if index.min() < 0 or index.max() > count - 1:
            continue
        slope, origin = np.polyfit(index, ticks, 1) if np.ptp(index) > 0 else (step, ticks[0])
        fitted = origin + slope * index
        if np.abs(fitted - ticks).max() <= 1.5 and abs(origin + slope * sign - anchor) <= 1.5:
            return index, float(slope)
    raise PerceptionFailed(f"the {axis} axis ticks are not evenly spaced from its ends")


def find_frame(keys: Keys, facts: PromptFacts) -> Frame:
    """The frame from the axes' ticks (their count must fit the prompt's table size).

    Raises:
        PerceptionFailed: No axis, or ticks that do not fit the table.
    """
    ink = near(keys, st.INK)
    row = int(np.argmax(ink.sum(axis=1)))
    col = int(np.argmax(ink.sum(axis=0)))
    height, width = keys.shape
    if ink[row].sum() < width // 4 or ink[:, col].sum() < height // 4 or row + 1 >= height:
        raise PerceptionFailed("no axis lines found")
    x_ends = _extent(ink[row])
    xs = _tick_marks(ink[row + 1], x_ends)
    x_index, step_x = _fit_ticks(xs, x_ends, facts.table.width, "x")
    up = ink[::-1, max(col - 1, 0)]  # rows counted from the bottom: y = 0 first
    y_ends = _extent(ink[::-1, col])
    ys = _tick_marks(up, y_ends)
    y_index, step_y = _fit_ticks(ys, y_ends, facts.table.height, "y")
    ppm_x, ppm_y = step_x / TICK_MINOR, step_y / TICK_MINOR
    if abs(ppm_x - ppm_y) > 0.01 * ppm_x:
        raise PerceptionFailed(f"the axes disagree on the scale: {ppm_x:g} and {ppm_y:g} px/m")
    ppm = ppm_x if len(xs) >= len(ys) else ppm_y  # ticks sit on whole pixels: more is better
    if abs(ppm - round(ppm)) < 0.3:  # whole pixels per metre are the usual setting
        ppm = float(round(ppm))
    step = ppm * TICK_MINOR
    x0 = float(np.median(xs - x_index * step))
    bottom = float(np.median(ys - y_index * step))
    return Frame(x0, height - 1 - bottom, ppm)


def canvas_of(frame: Frame, facts: PromptFacts, size: tuple[int, int]) -> CanvasSpec:
    """The canvas the renderer drew on, rebuilt from the frame and the prompt's facts.

    Raises:
        PerceptionFailed: The rebuilt canvas is not the image's size.
    """
    table_w = round(facts.table.width * frame.ppm)
    table_h = round(facts.table.height * frame.ppm)
    top = round(frame.y0 - facts.table.height * frame.ppm)
    left = round(frame.x0)
    spec = CanvasSpec(
        facts.table.width,
        facts.table.height,
        frame.ppm,
        left,
        size[0] - left - table_w,
        top,
        size[1] - top - table_h,
        facts.physics.ball_radius,
        facts.pockets.radius,
        tuple(facts.pockets.centers),
    )
    if spec.size != size or min(spec.right, spec.bottom, top) < 0:
        raise PerceptionFailed(f"the table frame does not fit an image of {size[0]}x{size[1]}")
    return spec
