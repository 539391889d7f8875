"""Drawing a slider scene with Pillow: the ``init.png`` models see and the gallery's picture.

The track is the x axis of the picture's scene coordinates (y = 0), so a scorer can mark
positions with ``picture.to_px(x, 0.0)`` without knowing the layout. The drawing depends on the
scene alone and Pillow writes no timestamps, so the bytes are the same on every run.
"""

from __future__ import annotations

from PIL import Image, ImageDraw

from bpb_core.picture import ScenePicture, font
from bpb_tiny.scene import SliderScene

WIDTH, SIDE, TOP, ABOVE, BELOW = 640, 40, 34, 96, 46
PUCK_PX = 10
ARROW_PX_PER_MPS = 60.0
BACKGROUND, INK, PUCK, ARROW = (250, 250, 245), (40, 40, 48), (30, 90, 200), (200, 60, 20)


def blank(scene: SliderScene) -> ScenePicture:
    """An empty canvas mapped to the track: x in ``[0, L]`` across, y = 0 on the track."""
    scale = (WIDTH - 2 * SIDE) / scene.length
    image = Image.new("RGB", (WIDTH, TOP + ABOVE + BELOW), BACKGROUND)
    return ScenePicture(image, SIDE, TOP, scale, ABOVE / scale)


def _track(draw: ImageDraw.ImageDraw, picture: ScenePicture, length: float) -> None:
    (x_left, y), (x_right, _) = picture.to_px(0.0, 0.0), picture.to_px(length, 0.0)
    draw.line((x_left, y, x_right, y), fill=INK, width=4)
    for x in (x_left, x_right):
        draw.rectangle((x - 3, y - 60, x + 3, y + 2), fill=INK)
    face = font(13)
    for i in range(5):
        tx, _ = picture.to_px(length * i / 4, 0.0)
        draw.line((tx, y + 4, tx, y + 12), fill=INK, width=2)
        draw.text((tx, y + 14), f"{length * i / 4:g}", fill=INK, font=face, anchor="mt")
    draw.text((x_right, y + 32), "x (m)", fill=INK, font=face, anchor="rt")


def _puck(draw: ImageDraw.ImageDraw, picture: ScenePicture, scene: SliderScene) -> None:
    px, py = picture.to_px(scene.x0, 0.0)
    r = PUCK_PX
    draw.ellipse((px - r, py - r, px + r, py + r), fill=PUCK, outline=INK)
    if scene.v0 == 0:
        return
    end = px + ARROW_PX_PER_MPS * scene.v0
    ay = py - 34
    head = 8 if scene.v0 > 0 else -8
    draw.line((px, ay, end, ay), fill=ARROW, width=3)
    draw.polygon([(end + head, ay), (end, ay - 6), (end, ay + 6)], fill=ARROW)
    label = f"{abs(scene.v0):.3f} m/s"
    draw.text(((px + end) / 2, ay - 8), label, fill=ARROW, font=font(14), anchor="mb")


def draw_scene(scene: SliderScene) -> ScenePicture:
    """The scene at t = 0: track, walls, ticks in metres, the puck and its velocity arrow."""
    picture = blank(scene)
    draw = ImageDraw.Draw(picture.image)
    _track(draw, picture, scene.length)
    _puck(draw, picture, scene)
    title = f"{scene.scene_id}: t = 0 s (horizon {scene.horizon:g} s)"
    draw.text((SIDE, 8), title, fill=INK, font=font(15))
    return picture


def init_png(scene: SliderScene) -> bytes:
    """The ``init.png`` bytes of ``scene``."""
    return draw_scene(scene).png()
