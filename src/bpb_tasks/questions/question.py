"""The shared shape of the billiards questions q1-q3: the common prompt, parse and expected answer.

A question supplies its text, JSON example, validator and ground-truth cut;
:class:`BilliardsQuestion` turns them into the :class:`~bpb_core.interfaces.Task` methods.
:class:`LabelQuestion` is what q1 and q2 share on top: one ``T``/``F`` per unit; Q1
(:class:`Q1Task`: for each object ball, did the cue ball touch it in [0, t]?) and Q2
(:class:`Q2Task`: for each wall, did the cue ball touch it?) close this module.

The common prompt, built from the scene alone, states the constants and laws of the scene's
physics, the table coordinates, the ball radius, the pockets and the horizon (SPEC section 5);
each task adds its question, the JSON format with an example, and the reply instruction
(reasoning first or JSON only). Nothing in it reads ground truth: the functions take a
:class:`~bpb_tasks.billiards.scene.model.Scene` and prompt options only.

People answer in the browser (``bpb human``) on the forms ``forms/<task>.html``: Q1 and Q2 are
ticks (a ticked ball or wall is ``T``, the rest ``F``, and "none of them" must be ticked to say
so); Q3 places every ball by dragging its marker over the scene image (onto a pocket for a
pocketed ball), by the arrow keys on a marker, by typing ``x,y``, or confirms it rests.
"""

from __future__ import annotations

import json
from abc import ABC, abstractmethod
from collections.abc import Mapping
from importlib import resources
from typing import Annotated, Any, ClassVar

from pydantic import BaseModel

from bpb_core.errors import BadInput, ParseFailure
from bpb_core.interfaces import ParsedAnswer, PromptOptions
from bpb_core.model_calls import ImagePart, Message, TextPart
from bpb_core.reply_json import extract
from bpb_tasks.billiards.scene.model import WALLS, Scene, Wall
from bpb_tasks.billiards.truth.final import FinalState
from bpb_tasks.questions.answers import (
    TF,
    Answers,
    BallId,
    Item,
    Q1Schema,
    Q2Schema,
    Upper,
    check_ids,
    load,
    schema_of,
)

MAX_VALUE = 64  # characters of a posted form value shown in an error
NONE = "none"  # the field of the Q1/Q2 forms' "none of them" box


def colour(ball_id: int) -> str:
    """CSS colour of ball ``ball_id`` as the renderer draws it (the browser forms)."""
    from bpb_tasks.billiards.render import canvas

    r, g, b = canvas.ball_colour(ball_id)
    return f"#{r:02x}{g:02x}{b:02x}"


def _num(value: float) -> str:
    return f"{value:g}"


def common_prompt(scene: Scene, options: PromptOptions) -> str:
    """Everything every task states before its question: the table size, coordinates and
    walls; the balls, their radius, the cue ball and where the initial state is shown; the
    pockets and the pocketing rule; the friction and collision laws; the horizon; and with
    ``state`` in the input mode the initial state as compact JSON."""
    w, h = _num(scene.table.width), _num(scene.table.height)
    ids = sorted(b.id for b in scene.balls)
    where = (
        "The image shows every ball with its id and the cue ball's velocity as an arrow "
        "labelled with its speed in m/s."
        if options.input_mode != "state"
        else "The initial state is given as JSON below."
    )
    pockets = scene.pockets
    pockets_text = "Pockets: none; no ball can leave the table."
    if pockets.centers and pockets.radius > 0:
        centres = ", ".join(f"({_num(x)}, {_num(y)})" for x, y in pockets.centers)
        pockets_text = (
            f"Pockets: {len(pockets.centers)} pockets of radius {_num(pockets.radius)} m centred "
            f"at {centres}. A ball is pocketed the first instant its centre comes within "
            f"{_num(pockets.radius)} m of a pocket centre, and it leaves the table."
        )
    p = scene.physics
    restitution = (
        "perfectly elastic (the normal component of velocity is reversed)"
        if p.wall_restitution == 1
        else f"with restitution {_num(p.wall_restitution)} (normal component scaled by it)"
    )
    parts = [
        f"You are looking at a billiards table (scene {scene.scene_id}). Predict what happens "
        f"from t = 0 until t = {_num(scene.horizon)} s using the physics below.",
        f"Table: {w} m along x by {h} m along y, seen from above. The origin (0, 0) is the "
        f"bottom-left corner, x grows to the right and y grows upward. Walls: LEFT is x = 0, "
        f"RIGHT is x = {w}, BOTTOM is y = 0, TOP is y = {h}.",
        f"Balls: {len(ids)} balls with ids {ids[0]}..{ids[-1]}, equal mass, radius "
        f"R = {_num(p.ball_radius)} m. Ball 0 is the cue ball; at t = 0 only the cue ball moves, "
        f"all others are at rest. {where} A ball touches a wall when its centre is R from the "
        f"wall, and two balls touch when their centres are 2R apart.",
        pockets_text,
        f"Friction: a moving ball decelerates at constant mu*g along its velocity, with "
        f"mu = {_num(p.mu)} and g = {_num(p.g)} m/s^2. After travelling a distance s its speed is "
        f"v(s) = sqrt(v0^2 - 2*mu*g*s); it stops after s_stop = v0^2 / (2*mu*g) and then stays at "
        f"rest until another ball hits it.\n"
        f"Collisions: ball-ball collisions are perfectly elastic and frictionless between equal "
        f"masses (the balls exchange the velocity components along the line of centres); wall "
        f"collisions are {restitution}. There is no spin.",
        f"Horizon: t = {_num(scene.horizon)} s. Anything that happens at or before "
        f"t = {_num(scene.horizon)} s counts.",
    ]
    if options.input_mode in ("image+state", "state"):
        balls = [
            {"id": b.id, "pos": list(b.pos), "vel": list(b.vel)}
            for b in sorted(scene.balls, key=lambda b: b.id)
        ]
        parts.append(f"Initial state at t = 0 (metres, m/s): {json.dumps({'balls': balls})}")
    return "\n\n".join(parts)


class BilliardsQuestion(ABC):
    """Base of q1, q2 and q3.

    Subclasses set the class attributes and implement the four abstract methods below.
    """

    name: ClassVar[str] = ""
    default_cot: ClassVar[bool] = False
    title: ClassVar[str] = ""

    @abstractmethod
    def question(self, scene: Scene, options: PromptOptions) -> str:
        """The task's question and answer format with an example."""

    @abstractmethod
    def example(self, scene: Scene) -> str:
        """A JSON example of the answer format for this scene."""

    def example_for(self, scene: Scene, options: PromptOptions) -> str:
        """The example this prompt shows (default :meth:`example`; a task whose format depends
        on the options, such as q3 with ``force_numeric``, overrides it)."""
        return self.example(scene)

    @abstractmethod
    def validate(self, value: Any, scene: Scene) -> dict[str, Any]:
        """Check a decoded JSON value; return it normalised or raise ParseFailure."""

    @abstractmethod
    def expected(self, truth: FinalState) -> dict[str, Any]:
        """The correct answer, in the task's answer format, from the ground truth."""

    @property
    def form_template(self) -> str:
        """Jinja2 source of the task's browser form (``bpb human``)."""
        return (
            resources.files("bpb_tasks.questions").joinpath(f"forms/{self.name}.html").read_text()
        )

    def prompt_text(self, scene: Scene, options: PromptOptions) -> str:
        """The whole text of the prompt: the common part, the question and how to reply
        (reasoning then JSON, or JSON only; stronger after a malformed answer)."""
        parts = [
            common_prompt(scene, options),
            f"Task {self.name.upper()}: {self.question(scene, options)}",
        ]
        example = self.example_for(scene, options)
        if options.cot:
            reply = (
                "Think step by step, then end your reply with the final answer as one JSON object "
                "in exactly the format above."
            )
        else:
            reply = (
                "Reply with the JSON object only, in exactly the format above, and no other text."
            )
        if options.escalation >= 1:
            reply += (
                "\nIMPORTANT: a previous reply to this question could not be read. The reply must "
                "contain one complete, valid JSON object (double quotes, no comments, no trailing "
                "commas) covering every item listed."
            )
        if options.escalation >= 2:
            reply += f"\nReturn exactly this shape with your own values:\n{example}"
        return "\n\n".join([*parts, reply])

    def messages(
        self, scene: Scene, image: bytes | None, options: PromptOptions
    ) -> tuple[Message, ...]:
        """One user message: the scene image (unless ``state`` mode) and the prompt text.

        Raises:
            BadInput: An image input mode without image bytes.
        """
        text = TextPart(self.prompt_text(scene, options))
        if options.input_mode == "state":
            return (Message("user", (text,)),)
        if image is None:
            raise BadInput(
                f"{scene.scene_id}: init.png: input mode {options.input_mode!r} needs it"
            )
        return (Message("user", (ImagePart(image), text)),)

    def parse(self, text: str, scene: Scene, options: PromptOptions) -> ParsedAnswer:
        """Extract the answer (first balanced object, or last valid one with CoT) and validate.

        Raises:
            ParseFailure: Nothing in ``text`` validates; never any other exception.
        """
        try:
            value, rule = extract(text, lambda v: self.validate(v, scene), cot=options.cot)
        except ParseFailure:
            raise
        except Exception as exc:  # a validator bug must still surface as a parse failure
            raise ParseFailure(f"{self.name}: {type(exc).__name__}: {exc}") from None
        return ParsedAnswer(value, rule)


class LabelQuestion(BilliardsQuestion):
    """Base of q1 and q2: one ``T``/``F`` per unit (object ball, wall), ticked in the browser.

    Attributes:
        key: The key naming the unit in an answer item (``id``, ``wall``).
        reader: The lenient model a reply is read with
            (:class:`~bpb_tasks.questions.answers.Answers` of the task's items).
        schema: The strict model of the normalised answer (:mod:`bpb_tasks.questions.answers`).
    """

    default_cot: ClassVar[bool] = True
    key: ClassVar[str] = ""
    reader: ClassVar[type[BaseModel]]
    schema: ClassVar[type[BaseModel]]

    @abstractmethod
    def units(self, scene: Scene) -> list[Any]:
        """The units to label, in answer order."""

    @abstractmethod
    def asked(self, scene: Scene) -> tuple[str, str]:
        """What the question names: each unit (``wall TOP, ...``), and all of them."""

    def question(self, scene: Scene, options: PromptOptions) -> str:
        each, every = self.asked(scene)
        return (
            f"For each {each}, does the cue ball (ball 0) touch it at any time in "
            f"[0, {scene.horizon:g}] s? Answer T (yes) or F (no) for {every}, as JSON:\n"
            f"{self.example(scene)}"
        )

    def check(self, got: list[Any], units: list[Any]) -> None:
        """Raise ParseFailure unless ``got`` (the answer's units) has every unit exactly once."""
        check_ids(self.name, got, units)

    def validate(self, value: Any, scene: Scene) -> dict[str, Any]:
        """Validate an answer: one T/F per unit, returned in :meth:`units` order."""
        answer: Any = load(self.reader, self.name, value)
        units = self.units(scene)
        self.check([getattr(a, self.key) for a in answer.answers], units)
        by_unit = {getattr(a, self.key): a.answer for a in answer.answers}
        return {"answers": [{self.key: u, "answer": by_unit[u]} for u in units]}

    def expected(self, truth: FinalState) -> dict[str, Any]:
        return {"answers": [label.model_dump() for label in getattr(truth, self.name)]}

    def field(self, unit: Any) -> str:
        """The browser form's field of ``unit``."""
        return str(unit)

    def example(self, scene: Scene) -> str:
        units = self.units(scene)
        items = [{self.key: u, "answer": "T" if n == 0 else "F"} for n, u in enumerate(units)]
        return json.dumps({"answers": items})

    def read_form(self, fields: Mapping[str, str], scene: Scene) -> dict[str, Any]:
        """Ticked units are ``T``, the others ``F``; ``none`` ticked says the cue ball touches
        none. A form with nothing ticked is no answer (an untouched page is not "no contact")."""
        units = self.units(scene)
        names = [self.field(u) for u in units]
        for key, value in fields.items():
            if key not in names and key != NONE:
                raise ValueError(f"{key}: not a field of this form")
            if value != "T":
                raise ValueError(f"{key}: a ticked box posts T, got {value[:MAX_VALUE]!r}")
        ticked = [name for name in names if name in fields]
        if NONE in fields and ticked:
            raise ValueError(f"{NONE}: ticked together with {ticked[0]}")
        if NONE not in fields and not ticked:
            raise ValueError(f"{NONE}: missing (tick what the cue ball touches, or 'none of them')")
        answers = [{self.key: u, "answer": "T" if self.field(u) in fields else "F"} for u in units]
        return {"answers": answers}

    def answer_schema(self) -> dict[str, Any]:
        """The JSON Schema of the normalised answer (``docs/schemas/<name>.answer.schema.json``)."""
        return schema_of(self.schema, self.name)


class BallAnswer(Item):
    """Q1 item: did the cue ball touch ball ``id``."""

    id: BallId
    answer: Annotated[TF, Upper]


class Q1Task(LabelQuestion):
    """Cue-ball collisions with each object ball (chain of thought on by default)."""

    name: ClassVar[str] = "q1"
    title: ClassVar[str] = "Ball collisions"
    key: ClassVar[str] = "id"
    reader = Answers[BallAnswer]
    schema = Q1Schema

    def units(self, scene: Scene) -> list[int]:
        """The object balls' ids, in order."""
        return sorted(b.id for b in scene.balls if b.id != 0)

    def field(self, unit: Any) -> str:
        return f"ball{unit}"

    def asked(self, scene: Scene) -> tuple[str, str]:
        return f"object ball {self.units(scene)}", "every one of them"

    def form_context(self, scene: Scene, image: bytes | None) -> dict[str, Any]:
        """The object balls to tick (``bpb human``)."""
        balls = [{"id": i, "colour": colour(i)} for i in self.units(scene)]
        return {"horizon": f"{scene.horizon:g}", "balls": balls}


class WallAnswer(Item):
    """Q2 item: did the cue ball touch ``wall``."""

    wall: Annotated[Wall, Upper]
    answer: Annotated[TF, Upper]


class Q2Task(LabelQuestion):
    """Cue-ball contacts with each wall (chain of thought on by default)."""

    name: ClassVar[str] = "q2"
    title: ClassVar[str] = "Wall contacts"
    key: ClassVar[str] = "wall"
    reader = Answers[WallAnswer]
    schema = Q2Schema

    def units(self, scene: Scene) -> list[Wall]:
        """The walls: TOP, BOTTOM, LEFT, RIGHT."""
        return list(WALLS)

    def asked(self, scene: Scene) -> tuple[str, str]:
        return "wall TOP, BOTTOM, LEFT and RIGHT", "all four walls"

    def check(self, got: list[Any], units: list[Any]) -> None:
        if len(got) != len(set(got)) or set(got) != set(WALLS):
            raise ParseFailure(f"q2: walls must be {list(WALLS)} once each, got {got}")

    def form_context(self, scene: Scene, image: bytes | None) -> dict[str, Any]:
        """The walls to tick (``bpb human``)."""
        return {"horizon": f"{scene.horizon:g}", "walls": list(WALLS)}
