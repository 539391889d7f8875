"""The fake server's other wire protocols: Anthropic Messages, Gemini generateContent and
OpenAI Responses, each read and answered in the provider's documented JSON format.

Each handler pulls the prompt text and images out of the provider's own request shape, asks the
server for the fault and correct answer (:meth:`FakeOpenAI.answer`), and replies with the
provider's body, including its usage fields: Anthropic ``usage.cache_read_input_tokens`` and a
``thinking`` block, Gemini ``usageMetadata.thoughtsTokenCount`` and a ``thought`` part, Responses
``output_tokens_details.reasoning_tokens`` and a ``reasoning`` item. Every protocol reports 1000
input tokens (100 of them cached) and 50 output tokens (20 of them reasoning), as the chat
endpoint does.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

from aiohttp import web

from bpb_testing.fakereplies import REFUSAL, reply_content
from bpb_testing.rules import anthropic_error, anthropic_rejection

if TYPE_CHECKING:
    from bpb_testing.fakeserver import FakeOpenAI

THOUGHT = "Thinking about where each object goes."
_FINISH = {  # how each API says a reply ended (see reply_content's kinds)
    "anthropic": {"stop": "end_turn", "length": "max_tokens", "refusal": "refusal",
                  "safety": "refusal"},
    "gemini": {"stop": "STOP", "length": "MAX_TOKENS", "refusal": "SAFETY", "safety": "SAFETY"},
}  # fmt: skip
_BLOCKED = [{"category": "HARM_CATEGORY_DANGEROUS_CONTENT", "probability": "HIGH", "blocked": True}]


def _walk(value: Any) -> list[dict[str, Any]]:
    """Every JSON object inside ``value``, depth first."""
    found: list[dict[str, Any]] = []
    if isinstance(value, dict):
        found.append(value)
        for inner in value.values():
            found.extend(_walk(inner))
    elif isinstance(value, list):
        for inner in value:
            found.extend(_walk(inner))
    return found


def image_blocks(body: dict[str, Any]) -> list[dict[str, Any]]:
    """The image blocks of a request in any protocol, with their bytes left out."""
    blocks = []
    for obj in _walk(body):
        kind = obj.get("type")
        if kind == "image_url":  # OpenAI chat
            url = str(obj.get("image_url", {}).get("url", ""))
            blocks.append({"format": "openai-chat", "media": url.split(";")[0][5:]})
        elif kind == "input_image":  # OpenAI Responses
            url = str(obj.get("image_url", ""))
            blocks.append({"format": "openai-responses", "media": url.split(";")[0][5:]})
        elif kind == "image" and isinstance(obj.get("source"), dict):  # Anthropic
            source = obj["source"]
            blocks.append(
                {"format": f"anthropic-{source.get('type')}", "media": source.get("media_type")}
            )
        for key in ("inline_data", "inlineData"):  # Gemini
            if isinstance(obj.get(key), dict):
                inline = obj[key]
                media = inline.get("mime_type") or inline.get("mimeType")
                blocks.append({"format": "gemini-inline", "media": media})
    return blocks


def _texts(body: dict[str, Any], keys: tuple[str, ...]) -> str:
    return "\n".join(
        str(obj[k]) for obj in _walk(body) for k in keys if isinstance(obj.get(k), str)
    )


def prompt_text(body: dict[str, Any]) -> tuple[str, int]:
    """All text of a chat request's messages and how many images they carry."""
    texts, images = [], 0
    for message in body.get("messages", []):
        content = message.get("content")
        if isinstance(content, str):
            texts.append(content)
            continue
        for part in content or []:
            if part.get("type") == "text":
                texts.append(part.get("text", ""))
            elif part.get("type") == "image_url":
                images += 1
    return "\n".join(texts), images


def request_prompt(protocol: str, body: dict[str, Any]) -> tuple[str, int]:
    """The prompt text of a request body in ``protocol`` (``openai-chat``,
    ``openai-responses``, ``anthropic`` or ``gemini``) and how many images it carries."""
    if protocol == "openai-chat":
        return prompt_text(body)
    if protocol == "anthropic":
        text = _texts({"s": body.get("system"), "m": body.get("messages")}, ("text",))
    elif protocol == "gemini":
        system = body.get("system_instruction") or body.get("systemInstruction")
        text = _texts({"s": system, "c": body.get("contents")}, ("text",))
    else:
        text = _texts({"i": body.get("instructions"), "m": body.get("input")}, ("text",))
    return text, len(image_blocks(body))


def anthropic_body(body: dict[str, Any], fault: str, answer: str) -> dict[str, Any]:
    """The Messages API reply to ``body`` for ``fault`` and the correct ``answer``."""
    content, finish = reply_content(fault, answer)
    blocks: list[dict[str, Any]] = []
    if body.get("thinking"):
        blocks.append({"type": "thinking", "thinking": THOUGHT, "signature": "fake-signature"})
    if content:  # an empty reply and a refusal have no text block
        blocks.append({"type": "text", "text": content})
    return {
        "id": f"msg_fake{time.time_ns()}",
        "type": "message",
        "role": "assistant",
        "model": body.get("model", "fake"),
        "content": blocks,
        "stop_reason": _FINISH["anthropic"][finish],
        "stop_sequence": None,
        "usage": {
            "input_tokens": 900,
            "cache_read_input_tokens": 100,
            "cache_creation_input_tokens": 0,
            "output_tokens": 50,
        },
    }


async def anthropic_messages(server: FakeOpenAI, request: web.Request) -> web.StreamResponse:
    """``POST /v1/messages``."""
    body = await request.json()
    server.record(request, "anthropic", body)
    rejected = anthropic_rejection(body)
    if rejected is not None:
        return anthropic_error(rejected)
    outcome = await server.answer(request, *request_prompt("anthropic", body), "anthropic")
    if isinstance(outcome, web.StreamResponse):
        return outcome
    return web.json_response(anthropic_body(body, *outcome))


def gemini_body(model: str, fault: str, answer: str) -> dict[str, Any]:
    """The generateContent reply of ``model`` for ``fault`` and the correct ``answer``."""
    content, finish = reply_content(fault, answer)
    return {
        "candidates": [_gemini_candidate(content, finish)],
        "usageMetadata": {
            "promptTokenCount": 1000,
            "cachedContentTokenCount": 100,
            "candidatesTokenCount": 30,
            "thoughtsTokenCount": 20,
            "totalTokenCount": 1050,
        },
        "modelVersion": model,
    }


async def gemini_generate(server: FakeOpenAI, request: web.Request) -> web.StreamResponse:
    """``POST /v1beta/models/{model}:generateContent``."""
    body = await request.json()
    server.record(request, "gemini", body)
    outcome = await server.answer(request, *request_prompt("gemini", body), "gemini")
    if isinstance(outcome, web.StreamResponse):
        return outcome
    model = request.match_info["model"].split(":")[0]
    return web.json_response(gemini_body(model, *outcome))


def _gemini_candidate(content: str, finish: str) -> dict[str, Any]:
    """A candidate: a blocked one has no ``content`` and says which rating blocked it; an empty
    one has a ``content`` with no parts."""
    candidate: dict[str, Any] = {"finishReason": _FINISH["gemini"][finish], "index": 0}
    if finish in ("refusal", "safety"):
        candidate["safetyRatings"] = _BLOCKED
        return candidate
    parts = [{"text": THOUGHT, "thought": True}, {"text": content}] if content else []
    candidate["content"] = {"role": "model", "parts": parts}
    return candidate


def _responses_output(body: dict[str, Any], content: str, finish: str) -> list[dict[str, Any]]:
    """The output items: the reasoning item (its summary only when the request asked for one,
    ``reasoning.summary``) and the message, whose content is a ``refusal`` item when the model
    declined; a reply the filter stopped has no message."""
    asked = (body.get("reasoning") or {}).get("summary")
    summary = [{"type": "summary_text", "text": THOUGHT}] if asked else []
    items: list[dict[str, Any]] = [{"type": "reasoning", "id": "rs_fake", "summary": summary}]
    if finish == "safety":
        return items
    part = {"type": "output_text", "text": content, "annotations": []}
    if finish == "refusal":
        part = {"type": "refusal", "refusal": REFUSAL}
    message = {"type": "message", "id": "msg_fake", "role": "assistant", "content": [part]}
    items.append({**message, "status": "completed" if finish == "stop" else "incomplete"})
    return items


def responses_body(body: dict[str, Any], fault: str, answer: str) -> dict[str, Any]:
    """The Responses API reply to ``body`` for ``fault`` and the correct ``answer``."""
    content, finish = reply_content(fault, answer)
    incomplete = {"length": "max_output_tokens", "safety": "content_filter"}.get(finish)
    return {
        "id": f"resp_fake{time.time_ns()}",
        "object": "response",
        "created_at": int(time.time()),
        "status": "incomplete" if incomplete else "completed",
        "incomplete_details": {"reason": incomplete} if incomplete else None,
        "model": body.get("model", "fake"),
        "output": _responses_output(body, content, finish),
        "usage": {
            "input_tokens": 1000,
            "input_tokens_details": {"cached_tokens": 100},
            "output_tokens": 50,
            "output_tokens_details": {"reasoning_tokens": 20},
            "total_tokens": 1050,
        },
    }


async def openai_responses(server: FakeOpenAI, request: web.Request) -> web.StreamResponse:
    """``POST /v1/responses``."""
    body = await request.json()
    server.record(request, "openai-responses", body)
    outcome = await server.answer(request, *request_prompt("openai-responses", body), "openai")
    if isinstance(outcome, web.StreamResponse):
        return outcome
    return web.json_response(responses_body(body, *outcome))


def add_protocol_routes(app: web.Application, server: FakeOpenAI) -> None:
    """Route the three provider protocols to ``server``."""

    def bind(handler: Any) -> Any:
        async def route(request: web.Request) -> web.StreamResponse:
            response: web.StreamResponse = await handler(server, request)
            return response

        return route

    app.router.add_post("/v1/messages", bind(anthropic_messages))
    app.router.add_post("/v1beta/models/{model}", bind(gemini_generate))
    app.router.add_post("/v1/responses", bind(openai_responses))
    app.router.add_post("/responses", bind(openai_responses))
