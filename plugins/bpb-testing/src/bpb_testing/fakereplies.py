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

_HINTED = ("429", "503", "529")  # faults whose reply carries Retry-After


def _error(status: int, openai: str, anthropic: str, gemini: str, message: str) -> dict[str, Any]:
    """One HTTP fault: its status, its type in each provider's error body, its message."""
    return {"status": status, "types": (openai, anthropic, gemini), "message": message}


# Bodies as each API documents its errors (docs/providers.md, "Error replies"); the OpenAI
# type doubles as its ``code`` (``model_not_found``, ``insufficient_quota``).
HTTP_FAULTS: dict[str, dict[str, Any]] = {
    "400": _error(400, "invalid_value", "invalid_request_error", "INVALID_ARGUMENT",
                  "Unsupported value: 'temperature' does not support 0 with this model."),
    "401": _error(401, "invalid_api_key", "authentication_error", "UNAUTHENTICATED",
                  "Incorrect API key provided."),
    "403": _error(403, "permission_denied", "permission_error", "PERMISSION_DENIED",
                  "Your API key does not have permission to use the specified resource."),
    "404": _error(404, "model_not_found", "not_found_error", "NOT_FOUND",
                  "The model `fake` does not exist or you do not have access to it."),
    "quota": _error(429, "insufficient_quota", "rate_limit_error", "RESOURCE_EXHAUSTED",
                    "You exceeded your current quota, please check your plan and billing "
                    "details. (insufficient_quota)"),
    "context": _error(400, "context_length_exceeded", "invalid_request_error",
                      "INVALID_ARGUMENT", "This model's maximum context length is 8192 tokens. "
                      "However, your messages resulted in 9000 tokens."),
    "429": _error(429, "rate_limit_exceeded", "rate_limit_error", "RESOURCE_EXHAUSTED",
                  "Rate limit reached for requests."),
    "500": _error(500, "server_error", "api_error", "INTERNAL", "injected 500"),
    "503": _error(503, "server_error", "overloaded_error", "UNAVAILABLE", "injected 503"),
    "529": _error(529, "server_error", "overloaded_error", "UNAVAILABLE", "injected 529"),
}  # fmt: skip
_PROTOCOLS = ("openai", "anthropic", "gemini")


def error_body(fault: str, protocol: str) -> dict[str, Any]:
    """The error body of HTTP ``fault`` in ``protocol``'s documented shape."""
    spec = HTTP_FAULTS[fault]
    kind = spec["types"][_PROTOCOLS.index(protocol)]
    message = spec["message"]
    if protocol == "anthropic":
        return {"type": "error", "error": {"type": kind, "message": message}}
    if protocol == "gemini":
        return {"error": {"code": spec["status"], "message": message, "status": kind}}
    return {"error": {"message": message, "type": kind, "param": None, "code": kind}}


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


REFUSAL = "I'm sorry, but I can't help with that request."
"""What a refusing model says (OpenAI's ``refusal`` field and Responses ``refusal`` item)."""


def reply_content(fault: str, answer: str) -> tuple[str, str]:
    """The reply text for ``fault`` and how it ended: ``stop``, ``length`` (cut at the token
    cap), ``refusal`` (the model declined) or ``safety`` (a safety filter blocked the reply);
    the text is empty for ``empty``, ``refusal`` and ``safety``, each protocol then saying so
    its own way."""
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
    if fault in ("refusal", "safety"):
        return "", fault
    return ("" if fault == "empty" else answer), "stop"


_CHAT_FINISH = {"stop": "stop", "length": "length", "refusal": "stop", "safety": "content_filter"}


def model_reply(model: str, fault: str, answer: str) -> dict[str, Any]:
    """A chat.completion body whose content depends on ``fault``: a refusal is the message's
    ``refusal`` with ``content`` null, a filtered reply ``finish_reason: content_filter`` with
    ``content`` null (OpenAI's chat completion object)."""
    content, finish = reply_content(fault, answer)
    message = {
        "role": "assistant",
        "content": None if finish in ("refusal", "safety") else content,
        "refusal": REFUSAL if finish == "refusal" else None,
    }
    return {
        "id": f"chatcmpl-fake-{time.time_ns()}",
        "object": "chat.completion",
        "created": int(time.time()),
        "model": model,
        "choices": [{"index": 0, "message": message, "finish_reason": _CHAT_FINISH[finish]}],
        "usage": {
            "prompt_tokens": 1000,
            "completion_tokens": 50,
            "total_tokens": 1050,
            "completion_tokens_details": {"reasoning_tokens": 20},
            "prompt_tokens_details": {"cached_tokens": 100},
        },
    }


async def fault_reply(
    request: web.Request, fault: str, retry_after: float, protocol: str = "openai"
) -> web.StreamResponse | None:
    """The reply for a transport or HTTP fault (an error body in ``protocol``'s shape:
    ``openai``, ``anthropic`` or ``gemini``), or ``None`` when the body is a normal one."""
    if fault in HTTP_FAULTS:
        headers = {"Retry-After": f"{retry_after:g}"} if fault in _HINTED else {}
        status = HTTP_FAULTS[fault]["status"]
        return web.json_response(error_body(fault, protocol), status=status, headers=headers)
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
