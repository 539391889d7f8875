"""Task ``slider_stop``: where is the puck at the horizon, and how many wall hits by then?

The answer is one JSON object ``{"x": <metres>, "bounces": <count>}``. The prompt is built from
the scene alone; the reply is read with bpb's balanced-object rule
(:func:`bpb_core.reply_json.extract`) and only :class:`~bpb_core.errors.ParseFailure` escapes.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

from bpb_core.errors import BadInput, ParseFailure
from bpb_core.interfaces import ParsedAnswer, PromptOptions
from bpb_core.model_calls import ImagePart, Message, TextPart
from bpb_core.reply_json import extract
from bpb_tiny.scene import SliderScene, SliderTruth

TOLERANCE_SHARE = 0.02
"""A position within this share of the track length counts as right."""

IMAGE_TEXT = (
    "The image shows the track with ticks in metres, the puck at t = 0 and its velocity as an "
    "arrow labelled with the speed in m/s (the arrow points the way it moves)."
)


def read_count(value: object) -> int | None:
    """A non-negative integer count (``2`` or ``2.0``), else ``None``; booleans are not."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    if isinstance(value, float) and not value.is_integer():
        return None
    return int(value) if value >= 0 else None


def read_position(value: object) -> float | None:
    """A finite number, else ``None``; booleans are not numbers here."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


def validate(value: Any, scene: SliderScene) -> dict[str, Any]:
    """The answer normalised to ``{"x": float, "bounces": int}``; ParseFailure otherwise."""
    if not isinstance(value, dict):
        raise ParseFailure("slider_stop: the answer must be a JSON object")
    x, bounces = read_position(value.get("x")), read_count(value.get("bounces"))
    if x is None or not 0.0 <= x <= scene.length:
        raise ParseFailure(f"slider_stop: x: must be a number in [0, {scene.length:g}]")
    if bounces is None:
        raise ParseFailure("slider_stop: bounces: must be a non-negative integer")
    return {"x": x, "bounces": bounces}


def prompt_text(scene: SliderScene, options: PromptOptions) -> str:
    """The whole prompt: world, what is shown, question, answer format and reply instruction."""
    length, h = f"{scene.length:g}", f"{scene.horizon:g}"
    parts = [
        f"A puck slides along a straight track (scene {scene.scene_id}). Positions are x in "
        f"metres from x = 0 to x = {length}; there is a wall at each end.",
        f"Physics: the puck is a point. While moving it decelerates at a constant "
        f"mu*g = {scene.mu_g:g} m/s^2, so from speed v it stops after v^2 / (2*mu*g) metres and "
        f"then stays at rest. A wall reverses its velocity and keeps its speed (elastic).",
    ]
    if options.input_mode != "state":
        parts.append(IMAGE_TEXT)
    if options.input_mode != "image":
        parts.append(f"Initial state: x0 = {scene.x0:g} m, v0 = {scene.v0:g} m/s (positive: "
                     f"toward x = {length}).")  # fmt: skip
    parts += [
        f"Question: where is the puck at t = {h} s, and how many times has it hit a wall in "
        f"[0, {h}] s? A position within {TOLERANCE_SHARE * scene.length:g} m counts as right.",
        'Answer as JSON: {"x": 0.42, "bounces": 1}',
        "Think step by step, then end with the JSON object."
        if options.cot
        else "Reply with the JSON object only.",
    ]
    if options.escalation:
        parts.append("A previous reply could not be read: give exactly one valid JSON object.")
    return "\n\n".join(parts)


class SliderStopTask:
    """The ``slider_stop`` task (answers without chain of thought by default)."""

    name: ClassVar[str] = "slider_stop"
    default_cot: ClassVar[bool] = False

    def messages(
        self, scene: SliderScene, image: bytes | None, options: PromptOptions
    ) -> tuple[Message, ...]:
        """One user message: ``init.png`` (unless ``state`` mode) and the prompt.

        Raises:
            BadInput: An image input mode without image bytes.
        """
        text = TextPart(prompt_text(scene, options))
        if options.input_mode == "state":
            return (Message("user", (text,)),)
        if image is None:
            raise BadInput(
                f"{scene.scene_id}: init.png: input mode {options.input_mode!r} needs it"
            )
        return (Message("user", (ImagePart(image), text)),)

    def parse(self, text: str, scene: SliderScene, options: PromptOptions) -> ParsedAnswer:
        """The answer in ``text``; raises ParseFailure and nothing else."""
        try:
            value, rule = extract(text, lambda v: validate(v, scene), cot=options.cot)
        except ParseFailure:
            raise
        except Exception as exc:  # a bug here must still read as an unreadable reply
            raise ParseFailure(f"slider_stop: {type(exc).__name__}: {exc}") from None
        return ParsedAnswer(value, rule)

    def expected(self, truth: SliderTruth) -> dict[str, Any]:
        """The correct answer."""
        return {"x": truth.x, "bounces": truth.bounces}
