"""An adapter that answers with the text of the prompt it receives.

bpb's prompts end with an example answer in the task's JSON format, so ``echo:prompt`` gives
answers that parse (and are usually wrong): a model-free way to watch a run go end to end.
``echo:upper`` shouts the prompt instead, which never parses: a way to watch re-asks happen.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from bpb_core import AdapterOptions, ModelRequest, ModelResponse, TextPart, Usage
from bpb_core.errors import BadInput

MODELS = ("prompt", "upper")


@dataclass
class EchoAdapter:
    """Replies with the text parts of the last user message."""

    name: str
    upper: bool = False

    async def complete(self, request: ModelRequest) -> ModelResponse:
        started = time.perf_counter()
        user = [m for m in request.messages if m.role == "user"]
        parts = user[-1].parts if user else ()
        text = "\n".join(p.text for p in parts if isinstance(p, TextPart))
        if self.upper:
            text = text.upper().replace("{", "(").replace("}", ")")
        return ModelResponse(
            text=text,
            usage=Usage(input_tokens=len(text.split()), output_tokens=len(text.split())),
            cost=None,  # nobody publishes a price for echoing; unknown, not zero
            latency=time.perf_counter() - started,
            model_id=self.name,
            finish_reason="stop",
        )


def make_adapter(model: str, options: AdapterOptions) -> EchoAdapter:
    """Factory bpb calls for ``echo:<model>``."""
    if model not in MODELS:
        raise BadInput(f"--adapter echo:{model}: unknown model; known: echo:prompt, echo:upper")
    return EchoAdapter(f"echo:{model}", upper=model == "upper")
