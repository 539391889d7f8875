"""The shared shape of the billiards questions q1-q3: prompt, parse and expected answer.

A question supplies its text, JSON example, validator and ground-truth cut; this base class turns
them into the :class:`~bpb_core.interfaces.Task` methods. The text every question starts with
(table, balls, pockets, physics, horizon) is :mod:`bpb_tasks.questions.prompt`.
:class:`LabelQuestion` is what q1 and q2 share on top: one ``T``/``F`` per unit.
"""

from __future__ import annotations

import json
from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any, ClassVar

from pydantic import BaseModel

from bpb_core.errors import BadInput, ParseFailure
from bpb_core.interfaces import ParsedAnswer, PromptOptions
from bpb_core.model_calls import ImagePart, Message, TextPart
from bpb_core.reply_json import extract
from bpb_tasks.billiards.scene import Scene
from bpb_tasks.billiards.truth import FinalState
from bpb_tasks.questions.answers import schema_of
from bpb_tasks.questions.prompt import common_prompt, reply_instruction


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
        """Jinja2 source of the task's browser form (``bpb human``; see
        :mod:`bpb_tasks.questions.browser`)."""
        from bpb_tasks.questions.browser import template

        return template(self.name)

    def prompt_text(self, scene: Scene, options: PromptOptions) -> str:
        """The whole text of the prompt."""
        return "\n\n".join(
            [
                common_prompt(scene, options),
                f"Task {self.name.upper()}: {self.question(scene, options)}",
                reply_instruction(options, self.example_for(scene, options)),
            ]
        )

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
        schema: The strict model of the normalised answer (:mod:`bpb_tasks.questions.answers`).
    """

    key: ClassVar[str] = ""
    schema: ClassVar[type[BaseModel]]

    @abstractmethod
    def units(self, scene: Scene) -> list[Any]:
        """The units to label, in answer order."""

    def field(self, unit: Any) -> str:
        """The browser form's field of ``unit``."""
        return str(unit)

    def example(self, scene: Scene) -> str:
        units = self.units(scene)
        items = [{self.key: u, "answer": "T" if n == 0 else "F"} for n, u in enumerate(units)]
        return json.dumps({"answers": items})

    def read_form(self, fields: Mapping[str, str], scene: Scene) -> dict[str, Any]:
        """Ticked units are ``T``, the others ``F``."""
        from bpb_tasks.questions.browser import read_ticks

        units = self.units(scene)
        ticked = read_ticks(fields, [self.field(u) for u in units])
        answers = [{self.key: u, "answer": "T" if self.field(u) in ticked else "F"} for u in units]
        return {"answers": answers}

    def answer_schema(self) -> dict[str, Any]:
        """The JSON Schema of the normalised answer (``docs/schemas/<name>.answer.schema.json``)."""
        return schema_of(self.schema, self.name)
