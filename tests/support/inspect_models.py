"""Inspect AI model APIs for tests (Inspect's custom model API): ``bpbtest/truth`` answers every
bpb prompt from the dataset's ground truth, ``bpbtest/example`` answers with the answer format's
example that ends each prompt (a bad model), ``bpbtest/down`` fails every call (Inspect records
an errored sample with no output). Importing this module registers them.
:class:`ExampleAdapter` gives ``bpb run`` the replies of ``bpbtest/example``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bpb_testing.fakereplies import PromptIndex, message_text
from inspect_ai.model import (
    ChatMessage,
    ContentText,
    GenerateConfig,
    ModelAPI,
    ModelOutput,
    modelapi,
)
from inspect_ai.tool import ToolChoice, ToolInfo

from bpb_core import ModelRequest, ModelResponse, Usage
from bpb_core.reply_json import balanced_objects


def prompt_text(messages: list[ChatMessage]) -> str:
    """The text parts of ``messages`` joined by newlines, as bpb's fake server reads them."""
    texts: list[str] = []
    for message in messages:
        if isinstance(message.content, str):
            texts.append(message.content)
        else:
            texts += [part.text for part in message.content if isinstance(part, ContentText)]
    return "\n".join(texts)


def example_answer(text: str) -> str:
    """The last JSON object of a prompt: the example of the answer format."""
    found = "{}"
    for candidate in balanced_objects(text):
        found = candidate
    return found


class BpbTestModel(ModelAPI):
    """``truth`` answers right; ``example`` answers with the format's example; ``down`` fails."""

    def __init__(
        self,
        model_name: str,
        base_url: str | None = None,
        api_key: str | None = None,
        config: GenerateConfig = GenerateConfig(),  # noqa: B008 (Inspect's own signature)
        data: str = "data",
        **model_args: Any,
    ) -> None:
        super().__init__(model_name, base_url, api_key, [], config)
        self.index = PromptIndex(Path(data)) if model_name == "truth" else None

    async def generate(
        self,
        input: list[ChatMessage],
        tools: list[ToolInfo],
        tool_choice: ToolChoice,
        config: GenerateConfig,
    ) -> ModelOutput:
        if self.model_name == "down":
            raise ConnectionError("bpbtest/down: the provider is down")
        text = prompt_text(input)
        reply = self.index.lookup(text)[1] if self.index else example_answer(text)
        return ModelOutput.from_content(model=self.model_name, content=reply)


@modelapi(name="bpbtest")
def bpbtest() -> type[ModelAPI]:
    return BpbTestModel


class ExampleAdapter:
    """The bpb adapter answering what ``bpbtest/example`` answers (the same replies in a run)."""

    name = "example"

    async def complete(self, request: ModelRequest) -> ModelResponse:
        reply = example_answer(message_text(request.messages))
        return ModelResponse(reply, Usage(), None, 0.0, "example")
