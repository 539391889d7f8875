"""The table frame read from the axes: where x = 0 and y = 0 are and how many pixels a metre is.

The renderer draws a one-pixel x axis under the table and a y axis left of it, with a tick every
:data:`~bpb_tasks.billiards.render_canvas.TICK_MINOR` metres starting at 0. The longest ink row
and column are the axes; the ticks next to them give the origin and the scale, and the canvas
the renderer drew on follows from them and the prompt's table and pockets.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from PIL import Image

from bpb_tasks.billiards import render_style as st
from bpb_tasks.billiards.render_canvas import TICK_MINOR, CanvasSpec
from bpb_tasks.billiards.vision.prompt_facts import PerceptionFailed, PromptFacts

Keys = NDArray[np.int32]


def colour_key(rgb: st.RGB) -> int:
    """One integer per colour, as :func:`image_keys` makes them."""
    return (rgb[0] << 16) | (rgb[1] << 8) | rgb[2]


def near(keys: Keys, rgb: st.RGB, tolerance: int = 6) -> NDArray[np.bool_]:
    """Where ``keys`` is within ``tolerance`` of ``rgb`` in every channel (the palette the
    images are drawn in moves some flat colours by a few levels)."""
    out = np.ones(keys.shape, dtype=bool)
    for shift, level in zip((16, 8, 0), rgb, strict=True):
        out &= np.abs(((keys >> shift) & 255) - level) <= tolerance
    return out


def shown(spec: CanvasSpec, rgb: st.RGB) -> int:
    """Key of the colour ``rgb`` becomes in the canvas's palette (what the image holds)."""
    from bpb_tasks.billiards.render_palette import palette_for

    pixel = palette_for(spec).quantize(Image.new("RGB", (1, 1), rgb)).convert("RGB")
    r, g, b = pixel.getpixel((0, 0))  # type: ignore[misc]
    return colour_key((r, g, b))


def image_keys(png: bytes) -> Keys:
    """The image as an (height, width) array of colour keys.

    Raises:
        PerceptionFailed: The bytes are not an image Pillow can read.
    """
    try:
        with Image.open(io.BytesIO(png)) as img:
            rgb = np.asarray(img.convert("RGB"), dtype=np.int32)
    except (OSError, ValueError) as exc:
        raise PerceptionFailed(f"the image cannot be read: {exc}") from None
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


def _longest_run(line: NDArray[np.bool_]) -> tuple[int, int]:
    """First and last index of the longest run of True in ``line``."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], line.astype(np.int8), [0]))))
    starts, ends = edges[::2], edges[1::2]
    longest = int(np.argmax(ends - starts))
    return int(starts[longest]), int(ends[longest]) - 1


def _ticks(
    axis_line: NDArray[np.bool_], beside: NDArray[np.bool_], expected: int, axis: str
) -> NDArray[np.intp]:
    """Tick positions: ink beside the axis, within the axis line's extent."""
    first, last = _longest_run(axis_line)
    found = np.flatnonzero(beside[first : last + 1]) + first
    if len(found) != expected:
        raise PerceptionFailed(f"the {axis} axis shows {len(found)} ticks, expected {expected}")
    return found


def find_frame(keys: Keys, facts: PromptFacts) -> Frame:
    """The frame from the axes' ticks (their count must match the prompt's table size).

    Raises:
        PerceptionFailed: No axis, or ticks that do not fit the table.
    """
    ink = near(keys, st.INK)
    row = int(np.argmax(ink.sum(axis=1)))
    col = int(np.argmax(ink.sum(axis=0)))
    height, width = keys.shape
    if ink[row].sum() < width // 4 or ink[:, col].sum() < height // 4 or row + 1 >= height:
        raise PerceptionFailed("no axis lines found")
    count_x = math.floor(facts.table.width / TICK_MINOR + 1e-9) + 1
    count_y = math.floor(facts.table.height / TICK_MINOR + 1e-9) + 1
    xs = _ticks(ink[row], ink[row + 1], count_x, "x")
    ys = _ticks(ink[:, col], ink[:, max(col - 1, 0)], count_y, "y")
    ppm_x = (xs[-1] - xs[0]) / ((count_x - 1) * TICK_MINOR)
    ppm_y = (ys[-1] - ys[0]) / ((count_y - 1) * TICK_MINOR)
    if abs(ppm_x - ppm_y) > 0.01 * ppm_x:
        raise PerceptionFailed(f"the axes disagree on the scale: {ppm_x:g} and {ppm_y:g} px/m")
    return Frame(float(xs[0]), float(ys[-1]), float(ppm_x))


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
