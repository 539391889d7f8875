"""What even a perfect reader of ``init.png`` could get right (``baseline:vision``'s ceiling).

The renderer pastes every ball at a whole pixel, so the image cannot place a centre closer than
half a pixel. :func:`perception_ceiling` moves every true centre to the pixel it is drawn at
(the grid read from the image itself, so any ``image.px_per_m`` is handled), keeps the true
velocities, simulates that scene and says which labels survive: ``pixel_ceiling_q1_set`` (every
Q1 label) and ``pixel_ceiling_q2`` (the wall set). Over a run the report shows their share by
horizon beside the accuracy of whatever read the image.
"""

from __future__ import annotations

from collections.abc import Callable

from bpb_core.errors import BpbError
from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.billiards.vision.frame import canvas_of, find_frame, image_keys, read_prompt


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
