"""Reply bodies of the fake OpenAI server: correct answers and the injected faults."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path
from typing import Any

from aiohttp import web

from bpb_core.layout import FINAL, scene_dir
from bpb_core.scene import WALLS, FinalState

_KEY = re.compile(r"^h([0-9.]+)_(\d+)/(q[123])$")
_IDS = re.compile(r"ids (\d+)\.\.(\d+)")
HTTP_FAULTS = {"429": 429, "500": 500, "401": 401, "400": 400, "503": 503}


def _truth(data: Path | None, key: str) -> FinalState | None:
    match = _KEY.match(key)
    if data is None or match is None:
        return None
    path = scene_dir(data, float(match.group(1)), int(match.group(2))) / FINAL
    try:
        return FinalState.model_validate_json(path.read_bytes())
    except (OSError, ValueError):
        return None


def _generic(task: str, prompt: str) -> dict[str, Any]:
    ids_match = _IDS.search(prompt)
    low, high = (int(ids_match.group(1)), int(ids_match.group(2))) if ids_match else (0, 6)
    ids = list(range(low, high + 1))
    if task == "q1":
        return {"answers": [{"id": i, "answer": "F"} for i in ids if i != 0]}
    if task == "q2":
        return {"answers": [{"wall": w, "answer": "F"} for w in WALLS]}
    return {"predictions": [{"id": i, "pos": [1.0, 0.5]} for i in ids]}


def answer_value(data: Path | None, key: str, prompt: str) -> dict[str, Any]:
    """The correct answer from ``final.json`` when known, else a valid all-F / centre answer."""
    task = key.rsplit("/", 1)[-1]
    final = _truth(data, key)
    if final is None:
        return _generic(task, prompt)
    if task == "q1":
        return {"answers": [label.model_dump() for label in final.q1]}
    if task == "q2":
        return {"answers": [label.model_dump() for label in final.q2]}
    return {
        "predictions": [
            {"id": p.id, "pos": None if p.pos is None else list(p.pos)} for p in final.predictions
        ]
    }


def answer_text(data: Path | None, key: str, prompt: str) -> str:
    """The correct answer as JSON text."""
    return json.dumps(answer_value(data, key, prompt))


def _content(fault: str, answer: str) -> tuple[str, str]:
    if fault == "cot":
        reasoning = (
            'Reasoning: the format looks like {"answers": [...]}; a draft {not json} and '
            'a brace in a string "}" do not count. The cue ball rolls on. Final answer: '
        )
        return reasoning + answer, "stop"
    if fault == "malformed":
        return "The cue ball probably hits something, but I cannot say which.", "stop"
    if fault == "partial":
        value = json.loads(answer)
        key = next(iter(value))
        value[key] = value[key][:2]
        return json.dumps(value), "stop"
    if fault == "length":
        return answer[: len(answer) // 2], "length"
    return answer, "stop"


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
        headers = {"Retry-After": f"{retry_after:g}"} if fault == "429" else {}
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
