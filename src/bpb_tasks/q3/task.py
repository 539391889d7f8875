"""Q3: every ball's centre at the horizon, ``null`` for a pocketed ball."""

from __future__ import annotations

import contextlib
import json
import math
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict, field_validator

from bpb_core.errors import ParseFailure
from bpb_core.interfaces import PromptOptions
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.truth.final import BallPosition, FinalState
from bpb_tasks.questions.answers import BallId, Item, Q3Schema, check_ids, load, schema_of
from bpb_tasks.questions.question import MAX_VALUE, BilliardsQuestion, colour

POCKETED = "pocket"


class PositionAnswer(Item):
    """Q3 item: centre of ball ``id`` at the horizon, ``None`` for pocketed."""

    id: BallId
    pos: tuple[float, float] | None

    @field_validator("pos", mode="before")
    @classmethod
    def _numbers(cls, value: Any) -> Any:
        if value is None:
            return None
        if not isinstance(value, list | tuple) or len(value) != 2:
            raise ValueError("pos must be [x, y] or null")
        if any(isinstance(c, bool) or not isinstance(c, int | float) for c in value):
            raise ValueError("pos must hold two numbers")
        if not all(math.isfinite(c) for c in value):
            raise ValueError("pos must be finite")
        return value


class Q3Answer(BaseModel):
    """``{"predictions": [{"id": 0, "pos": [x, y]}, ...]}``; ``pos`` null when pocketed."""

    model_config = ConfigDict(extra="ignore", frozen=True)
    predictions: list[PositionAnswer]


def _listed(predictions: Sequence[PositionAnswer | BallPosition]) -> dict[str, Any]:
    """The answer format of ``predictions`` (``pos`` a list, or ``None``)."""
    listed = [{"id": p.id, "pos": None if p.pos is None else list(p.pos)} for p in predictions]
    return {"predictions": listed}


def _position(key: str, value: str, scene: Scene) -> list[float] | None:
    if value == POCKETED:
        return None
    parts = value.split(",")
    try:
        x, y = (float(p) for p in parts) if len(parts) == 2 else (math.nan, math.nan)
    except ValueError:
        x = y = math.nan
    if not (math.isfinite(x) and math.isfinite(y)):
        shown = value[:MAX_VALUE]
        raise ValueError(f"{key}: expected 'x,y' in metres or {POCKETED!r}, got {shown!r}")
    if not (0 <= x <= scene.table.width and 0 <= y <= scene.table.height):
        raise ValueError(f"{key}: ({x:g}, {y:g}) is off the table")
    return [round(x, 4), round(y, 4)]


class Q3Task(BilliardsQuestion):
    """Final positions of all balls (chain of thought off by default, as in the paper)."""

    name: ClassVar[str] = "q3"
    title: ClassVar[str] = "Final positions"

    def example(self, scene: Scene, pocketed: bool = True) -> str:
        """The example, its last ball pocketed unless ``pocketed`` is false."""
        ids = sorted(b.id for b in scene.balls)
        items: list[dict[str, Any]] = [{"id": i, "pos": [1.2345, 0.5]} for i in ids]
        if pocketed and len(items) > 1:
            items[-1]["pos"] = None
        return json.dumps({"predictions": items})

    def example_for(self, scene: Scene, options: PromptOptions) -> str:
        """With ``force_numeric`` no ball of the example is null: the prompt forbids it."""
        return self.example(scene, pocketed=not options.force_numeric)

    def question(self, scene: Scene, options: PromptOptions) -> str:
        ids = sorted(b.id for b in scene.balls)
        w, h = scene.table.width, scene.table.height
        text = (
            f"Where is the centre of every ball {ids} at t = {scene.horizon:g} s? Give [x, y] in "
            f"metres (x in [0, {w:g}], y in [0, {h:g}], up to 4 decimals)"
        )
        if options.force_numeric:
            text += (
                ". Give numeric coordinates for every ball, never null: if you think a ball was "
                "pocketed, give your best estimate of where it is"
            )
        else:
            text += ", or null for a ball that was pocketed"
        return f"{text}. Answer as JSON:\n{self.example_for(scene, options)}"

    def validate(self, value: Any, scene: Scene) -> dict[str, Any]:
        """Validate a Q3 answer: every ball once, at least one number, positions on the table."""
        answer = load(Q3Answer, "q3", value)
        check_ids("q3", [p.id for p in answer.predictions], [b.id for b in scene.balls])
        if all(p.pos is None for p in answer.predictions):
            raise ParseFailure("q3: predictions: at least one position must be numeric")
        width, height = scene.table.width, scene.table.height
        for p in answer.predictions:
            if p.pos is not None and not (0 <= p.pos[0] <= width and 0 <= p.pos[1] <= height):
                where = f"ball {p.id} at {list(p.pos)}"
                raise ParseFailure(f"q3: predictions: {where} is off the table")
        return _listed(sorted(answer.predictions, key=lambda p: p.id))

    def expected(self, truth: FinalState) -> dict[str, Any]:
        return _listed(truth.predictions)

    def form_context(self, scene: Scene, image: bytes | None) -> dict[str, Any]:
        """Draggable markers at the balls' starting pixels and pocket drop zones on the image
        (``bpb human``). The image's frame (origin and scale) is read from its axes, as
        ``baseline:vision`` reads it, so the markers sit on the balls whatever the dataset's
        image settings; ``frame`` is ``None`` when the image has no readable axes: the form
        then asks for numbers."""
        from bpb_tasks.billiards.vision.frame import (
            PerceptionFailed,
            PromptFacts,
            find_frame,
            image_keys,
        )

        frame = None
        if image is not None:
            ids = tuple(b.id for b in scene.balls)
            facts = PromptFacts(
                scene.scene_id, scene.horizon, scene.table, scene.physics, scene.pockets, ids
            )
            with contextlib.suppress(PerceptionFailed):
                found = find_frame(image_keys(image), facts)
                frame = {"x0": found.x0, "y0": found.y0, "ppm": found.ppm}
        balls = [
            {"id": b.id, "x": b.pos[0], "y": b.pos[1], "colour": colour(b.id)} for b in scene.balls
        ]
        return {
            "balls": sorted(balls, key=lambda b: int(b["id"])),
            "table": [scene.table.width, scene.table.height],
            "radius": scene.physics.ball_radius,
            "pockets": [list(c) for c in scene.pockets.centers],
            "pocket_radius": scene.pockets.radius,
            "frame": frame,
            "horizon": f"{scene.horizon:g}",
        }

    def read_form(self, fields: Mapping[str, str], scene: Scene) -> dict[str, Any]:
        """Every ball's ``pos<id>``: ``x,y`` in metres or ``pocket`` (one per ball, none empty)."""
        names = {f"pos{b.id}": b.id for b in scene.balls}
        for key in fields:
            if key not in names:
                raise ValueError(f"{key}: not a field of this form")
        missing = [key for key in names if not fields.get(key, "").strip()]
        if missing:  # an untouched form is no answer: "rests" says a ball stays
            where = f"place ball {names[missing[0]]} or confirm it rests"
            raise ValueError(f"{missing[0]}: missing ({where}; every ball needs a place)")
        predictions = [{"id": i, "pos": _position(k, fields[k], scene)} for k, i in names.items()]
        return {"predictions": sorted(predictions, key=lambda p: int(p["id"]))}

    def answer_schema(self) -> dict[str, Any]:
        """The JSON Schema of the normalised answer (``docs/schemas/q3.answer.schema.json``)."""
        return schema_of(Q3Schema, self.name)
