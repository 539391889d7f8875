"""The failure gallery's picture of a billiards scene.

It is the scene's ``trajectory.png`` (or ``init.png``), mapped to table metres with the image
geometry recorded in ``dataset.json`` (``config.image``); when the images or the geometry are
missing, a plain table is drawn instead.
"""

from __future__ import annotations

import json
from pathlib import Path

from PIL import Image, ImageDraw

from bpb_core.layout import MANIFEST
from bpb_core.picture import ScenePicture, font
from bpb_tasks.billiards.scene.model import Scene

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
        draw.text((px, py), str(ball.id), fill=(0, 0, 0), anchor="mm", font=font(int(r * 1.2)))
    return picture
