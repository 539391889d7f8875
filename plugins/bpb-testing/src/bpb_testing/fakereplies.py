"""What the fake OpenAI server answers: the correct answer for a known prompt, and the injected
faults."""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path
from typing import Any, get_args

from aiohttp import web

from bpb_core.interfaces import InputMode, PromptOptions
from bpb_core.layout import FINAL, INIT, iter_scene_keys
from bpb_core.model_calls import Message, TextPart
from bpb_core.reply_json import balanced_objects

HTTP_FAULTS = {"429": 429, "500": 500, "401": 401, "400": 400, "503": 503, "529": 529}
_HINTED = ("429", "503", "529")  # faults whose reply carries Retry-After
UNKNOWN = "unknown/unknown"
_ESCALATIONS = (0, 1, 2)


def prompt_key(text: str) -> str:
    """A digest of a prompt's text, the index's key."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


class PromptIndex:
    """Every prompt bpb could send about a dataset, mapped to its ``scene/task`` key and the
    correct answer.

    Built by asking each of the dataset family's tasks for its messages under every prompt
    option (input mode, chain of thought, force-numeric, escalation), so the server knows what
    it is asked without parsing any task's wording.
    """

    def __init__(self, data: Path | None) -> None:
        self.entries: dict[str, tuple[str, str]] = {}
        if data is not None:
            self._build(data)

    def _build(self, data: Path) -> None:
        from bpb_core.dataset.reader import dataset_family
        from bpb_core.registry import make_registry
        from bpb_core.validated_files import read_model

        registry = make_registry()
        family = dataset_family(None, data, registry)
        tasks = {name: registry.task(name) for name in registry.tasks_for(family.name)}
        variants = [
            PromptOptions(mode, cot, numeric, escalation)
            for mode in get_args(InputMode)
            for cot in (False, True)
            for numeric in (False, True)
            for escalation in _ESCALATIONS
        ]
        for key in iter_scene_keys(data):
            scene = read_model(key.dir(data) / INIT, family.scene_model)
            truth = read_model(key.dir(data) / FINAL, family.truth_model)
            for name, task in tasks.items():
                answer = json.dumps(task.expected(truth))
                for options in variants:
                    text = message_text(task.messages(scene, b"image", options))
                    self.entries[prompt_key(text)] = (f"{key.scene_id}/{name}", answer)

    def lookup(self, text: str) -> tuple[str, str]:
        """``(scene/task key, correct answer JSON)``; for an unknown prompt, ``unknown/unknown``
        and the last JSON object in the prompt (the answer format's example)."""
        found = self.entries.get(prompt_key(text))
        if found is not None:
            return found
        example = ""
        for candidate in balanced_objects(text):
            example = candidate
        return UNKNOWN, example or "{}"


def message_text(messages: tuple[Message, ...]) -> str:
    """All text parts of ``messages``, joined by newlines (images left out)."""
    return "\n".join(p.text for m in messages for p in m.parts if isinstance(p, TextPart))


def _content(fault: str, answer: str) -> tuple[str, str]:
    if fault == "cot":
        reasoning = (
            'Reasoning: the format looks like {"answers": [...]}; a draft {not json} and '
            'a brace in a string "}" do not count. Everything moves on. Final answer: '
        )
        return reasoning + answer, "stop"
    if fault == "malformed":
        return "Something probably happens, but I cannot say what.", "stop"
    if fault == "partial":
        value = json.loads(answer)
        key = next(iter(value))
        value[key] = value[key][:2]
        return json.dumps(value), "stop"
    if fault == "length":
        return answer[: len(answer) // 2], "length"
    return answer, "stop"


def reply_content(fault: str, answer: str) -> tuple[str, str]:
    """The reply text for ``fault`` and its finish reason (``stop`` or ``length``)."""
    return _content(fault, answer)


def model_reply(model: str, fault: str, answer: str) -> dict[str, Any]:
    """A chat.completion body whose content depends on ``fault``."""
    content, finish = _content(fault, answer)
    return {
        "id": f"chatcmpl-fake-{time.time_ns()}",
        "object": "chat.completion",
        "created": int(time.time()),
        "model": model,
        "choices": [
            {
                "index": 0,
                "message": {"role": "assistant", "content": content},
                "finish_reason": finish,
            }
        ],
        "usage": {
            "prompt_tokens": 1000,
            "completion_tokens": 50,
            "total_tokens": 1050,
            "completion_tokens_details": {"reasoning_tokens": 20},
            "prompt_tokens_details": {"cached_tokens": 100},
        },
    }


async def fault_reply(
    request: web.Request, fault: str, retry_after: float
) -> web.StreamResponse | None:
    """The reply for a transport or HTTP fault, or ``None`` when the body is a normal one."""
    if fault in HTTP_FAULTS:
        headers = {"Retry-After": f"{retry_after:g}"} if fault in _HINTED else {}
        error = {"error": {"message": f"injected {fault}", "type": "fake", "code": fault}}
        return web.json_response(error, status=HTTP_FAULTS[fault], headers=headers)
    if fault == "nonjson":
        return web.Response(text="<html>502 gateway</html>", content_type="application/json")
    if fault == "truncated":
        response = web.StreamResponse(status=200, headers={"Content-Type": "application/json"})
        response.content_length = 4096
        await response.prepare(request)
        await response.write(b'{"id": "chatcmpl-cut", "choices": [{"ind')
        if request.transport is not None:
            request.transport.close()
        return response
    return None
