"""A scene drawn for the failure gallery: an RGB image, its coordinate mapping and a legend.

A scene family makes the picture (:class:`~bpb_core.capabilities.Picturing`); each task's scorer
draws its marks on it (:class:`~bpb_core.capabilities.DrawsOverlay`) and adds legend entries;
core puts the legend in a band above the image, so no mark covers the scene.
"""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from typing import Literal

from PIL import Image, ImageDraw, ImageFont

RGB = tuple[int, int, int]
Mark = Literal["ring", "ring-cross", "line", "square", "triangle"]
LEGEND_BACKGROUND: RGB = (24, 28, 36)


@dataclass(frozen=True)
class LegendEntry:
    """One explained mark: its shape, colour and label."""

    label: str
    colour: RGB
    mark: Mark


@dataclass
class ScenePicture:
    """An RGB image of a scene with a linear mapping from scene coordinates (y up) to pixels.

    Attributes:
        image: The picture, drawn on in place.
        left, top: Pixel position of the scene point ``(0, height)``.
        scale: Pixels per scene unit (metre).
        height: Height of the scene's frame in scene units.
        legend: Entries added by the overlays, shown once each.
    """

    image: Image.Image
    left: float
    top: float
    scale: float
    height: float
    legend: list[LegendEntry] = field(default_factory=list)

    def to_px(self, x: float, y: float) -> tuple[float, float]:
        """Pixel of scene point ``(x, y)``."""
        return self.left + x * self.scale, self.top + (self.height - y) * self.scale

    def explain(self, label: str, colour: RGB, mark: Mark) -> None:
        """Add a legend entry unless an equal one is there."""
        entry = LegendEntry(label, colour, mark)
        if entry not in self.legend:
            self.legend.append(entry)

    def png(self) -> bytes:
        """The picture below its legend band, as PNG bytes."""
        image = self.image
        if self.legend:
            image = _with_legend(image, self.legend, font(max(14, round(image.width / 70))))
        buffer = io.BytesIO()
        image.save(buffer, format="PNG", optimize=False)
        return buffer.getvalue()


def font(size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    """Pillow's built-in scalable font at ``size`` pixels."""
    return ImageFont.load_default(max(size, 8))


def _with_legend(
    image: Image.Image,
    legend: list[LegendEntry],
    face: ImageFont.FreeTypeFont | ImageFont.ImageFont,
) -> Image.Image:
    band = round(face.size * 2.2) if isinstance(face, ImageFont.FreeTypeFont) else 30
    framed = Image.new("RGB", (image.width, image.height + band), LEGEND_BACKGROUND)
    framed.paste(image, (0, band))
    draw = ImageDraw.Draw(framed)
    y, r = band // 2, band // 4
    step = framed.width // max(len(legend), 1)
    for i, entry in enumerate(legend):
        x = 16 + i * step
        _mark(draw, entry, x, y, r)
        draw.text((x + 3 * r, y), entry.label, fill=entry.colour, font=face, anchor="lm")
    return framed


def _mark(draw: ImageDraw.ImageDraw, entry: LegendEntry, x: int, y: int, r: int) -> None:
    if entry.mark == "line":
        draw.line((x, y, x + 2 * r, y), fill=entry.colour, width=2)
        return
    if entry.mark in ("square", "triangle"):
        draw.polygon(shape(entry.mark, x + r, y, r), outline=entry.colour, width=3)
        return
    draw.ellipse((x, y - r, x + 2 * r, y + r), outline=entry.colour, width=3)
    if entry.mark == "ring-cross":
        draw.line((x + r * 0.4, y - r * 0.6, x + r * 1.6, y + r * 0.6), fill=entry.colour, width=3)


def shape(
    mark: Literal["square", "triangle"], x: float, y: float, r: float
) -> list[tuple[float, float]]:
    """The corners of a square or an upward triangle of half-size ``r`` centred on ``(x, y)``
    (overlays draw them; the legend shows the same)."""
    if mark == "square":
        return [(x - r, y - r), (x + r, y - r), (x + r, y + r), (x - r, y + r)]
    h = r * 1.15
    return [(x, y - h), (x + h, y + h * 0.7), (x - h, y + h * 0.7)]
