"""A local OpenAI-compatible chat server with fault injection, for tests and ``benchmarks/run.py``.

It answers ``POST /v1/chat/completions`` (and, in their own wire formats, Anthropic's
``/v1/messages``, Gemini's ``/v1beta/models/MODEL:generateContent`` and OpenAI's
``/v1/responses``: :mod:`bpb_testing.protocols`) the way a model would: pointed at a
dataset, it knows every prompt bpb could send about it
(:class:`~bpb_testing.fakereplies.PromptIndex`), so it recognises the scene and task it
is asked and answers correctly from the ground truth; an unknown prompt is answered with the
example answer the prompt itself shows. It injects the faults it was told to:

- ``ok``: a correct answer (``cot``: reasoning with braces, then the answer);
- ``429``, ``503``, ``529`` (with Retry-After), ``500``, ``401``, ``403``, ``404``, ``400``,
  ``quota`` (429 ``insufficient_quota``), ``context`` (400 ``context_length_exceeded``): HTTP
  errors, each body in the protocol's documented error shape;
- ``hang``: no reply for ``hang`` seconds (past the client's timeout), then a correct one;
- ``truncated``: the body stops before its Content-Length and the connection drops;
- ``nonjson``: a 200 whose body is HTML; ``malformed``: prose with no JSON;
- ``partial``: JSON missing items; ``length``: an answer cut off at the token cap
  (``finish_reason: length``, Anthropic ``stop_reason: max_tokens``, Gemini ``MAX_TOKENS``,
  Responses ``incomplete_details.reason: max_output_tokens``);
- ``empty``: a reply with no text; ``refusal``: the model declines (OpenAI's ``refusal`` field
  and Responses ``refusal`` item, Anthropic ``stop_reason: refusal``, Gemini ``SAFETY``);
  ``safety``: a safety filter blocks the reply (``finish_reason: content_filter``, Responses
  ``incomplete_details.reason: content_filter``, Anthropic ``refusal``, Gemini ``SAFETY``).

With ``bill_max_tokens`` the chat endpoint bills every reply the most output a call may bill
(``completion_tokens`` = the request's ``max_completion_tokens`` or ``max_tokens``), the worst
case a spending cap must hold against. With ``keep_bodies`` ``GET /requests`` also gives each
request's whole body (a batch line must be the synchronous request: a test compares them).

Faults are given per ``scene/task`` key as a list consumed one per request (``{"h1_0000/TASK":
["429", "500"]}``; then ``ok``), and optionally as a ``schedule`` cycled over all requests.
``GET /stats`` returns request counts per key and arrival times per phase (``POST /phase``);
``GET /requests`` what the recent requests carried (parameters, headers, image blocks; no text).
The same port serves each provider's batch API (OpenAI's Files and Batch APIs, Anthropic's
Message Batches, Gemini's batch mode: :mod:`bpb_testing.batches`, config key ``batch``), whose
requests are answered with the same replies and faults.
Run it with ``python -m bpb_testing.fakeserver --port 0``; it prints ``PORT <n>`` when ready.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

from aiohttp import web

from bpb_testing.batches import BatchStore, add_batch_routes
from bpb_testing.fakereplies import PromptIndex, fault_reply, model_reply
from bpb_testing.protocols import add_protocol_routes, image_blocks, prompt_text

_CONVERSATION = frozenset({"messages", "contents", "input", "system", "system_instruction"})
_KEEP_REQUESTS = 200
_SECRET_HEADERS = frozenset({"authorization", "x-api-key", "x-goog-api-key", "api-key"})


class FakeOpenAI:
    """State and handlers of the fake server."""

    def __init__(self, config: dict[str, Any]) -> None:
        self.data = Path(config["data"]) if config.get("data") else None
        self.prompts = PromptIndex(self.data)
        self.latency = float(config.get("latency", 0.0))
        self.configure(config)
        self.counts: Counter[str] = Counter()
        self.total = 0
        self.images = 0
        self.auth_seen = 0
        self.phase = "default"
        self.phases: dict[str, dict[str, Any]] = {}
        self.requests: list[dict[str, Any]] = []
        self.batches = BatchStore(self, config.get("batch", {}))

    def configure(self, config: dict[str, Any]) -> None:
        """Replace the fault plan (keys ``faults``, ``schedule``, ``retry_after``, ``hang``,
        ``latency``, ``bill_max_tokens``)."""
        self.faults: dict[str, list[str]] = config.get("faults", {})
        self.schedule: list[str] = config.get("schedule", [])
        self.retry_after = float(config.get("retry_after", 0.2))
        self.hang = float(config.get("hang", 30.0))
        self.latency = float(config.get("latency", self.latency))
        self.bill_max_tokens = bool(config.get("bill_max_tokens", False))
        self.keep_bodies = bool(config.get("keep_bodies", False))
        if hasattr(self, "batches"):
            self.batches.configure(config.get("batch", {}))

    def _fault(self, key: str, seen: int) -> str:
        plan = self.faults.get(key) or self.faults.get("*/" + key.split("/")[-1]) or []
        if seen < len(plan):
            return plan[seen]
        if self.schedule and key not in self.faults:
            return self.schedule[(self.total - 1) % len(self.schedule)]
        return "ok"

    def _arrive(self) -> None:
        now = time.time()
        phase = self.phases.setdefault(self.phase, {"count": 0, "first": now, "last": now})
        phase["count"] += 1
        phase["last"] = now

    def plan(self, text: str, images: int) -> tuple[str, str, str]:
        """Count one request for a prompt and give its ``scene/task`` key, its fault and the
        correct answer (the requests of a provider batch come this way, with no HTTP request
        of their own: :mod:`bpb_testing.batches`)."""
        self._arrive()
        self.images += images
        key, answer = self.prompts.lookup(text)
        seen = self.counts[key]
        self.counts[key] += 1
        self.total += 1
        return key, self._fault(key, seen), answer

    async def answer(
        self, request: web.Request, text: str, images: int, protocol: str = "openai"
    ) -> tuple[str, str] | web.StreamResponse:
        """The fault and correct answer for a prompt, or the reply of a transport/HTTP fault
        (an error body in ``protocol``'s shape: ``openai``, ``anthropic`` or ``gemini``)."""
        if request.headers.get("Authorization") or request.headers.get("x-api-key"):
            self.auth_seen += 1
        _, fault, answer = self.plan(text, images)
        if self.latency:
            await asyncio.sleep(self.latency)
        if fault == "hang":
            await asyncio.sleep(self.hang)
        special = await fault_reply(request, fault, self.retry_after, protocol)
        return special if special is not None else (fault, answer)

    async def chat(self, request: web.Request) -> web.StreamResponse:
        """``POST /v1/chat/completions``."""
        body = await request.json()
        self.record(request, "openai-chat", body)
        outcome = await self.answer(request, *prompt_text(body))
        if isinstance(outcome, web.StreamResponse):
            return outcome
        reply = model_reply(body.get("model", "fake"), *outcome)
        cap = body.get("max_completion_tokens") or body.get("max_tokens")
        if self.bill_max_tokens and isinstance(cap, int):
            usage = reply["usage"]
            usage["completion_tokens"] = cap
            usage["total_tokens"] = usage["prompt_tokens"] + cap
        return web.json_response(reply)

    def record(self, request: web.Request, protocol: str, body: dict[str, Any]) -> None:
        """Keep what a request carried, without its text or image bytes (``GET /requests``);
        with ``keep_bodies``, its whole body too (``body``)."""
        self.requests.append(
            {
                **({"body": body} if self.keep_bodies else {}),
                "protocol": protocol,
                "path": request.path,
                "query": dict(request.query),
                "headers": {
                    k.lower(): "***" if k.lower() in _SECRET_HEADERS else v
                    for k, v in request.headers.items()
                },
                "params": {k: v for k, v in body.items() if k not in _CONVERSATION},
                "images": image_blocks(body),
            }
        )
        del self.requests[:-_KEEP_REQUESTS]

    async def requests_seen(self, request: web.Request) -> web.Response:
        """``GET /requests``: the recorded requests, oldest first."""
        return web.json_response(self.requests)

    async def stats(self, request: web.Request) -> web.Response:
        """``GET /stats``: counts per key, totals and phases."""
        return web.json_response(
            {
                "counts": dict(self.counts),
                "total": self.total,
                "images": self.images,
                "auth_seen": self.auth_seen,
                "phases": self.phases,
            }
        )

    async def set_phase(self, request: web.Request) -> web.Response:
        """``POST /phase`` with ``{"name": ...}``: label the following arrivals."""
        self.phase = str((await request.json()).get("name", "default"))
        return web.json_response({"phase": self.phase})

    async def set_config(self, request: web.Request) -> web.Response:
        """``POST /config``: replace the fault plan."""
        self.configure(await request.json())
        return web.json_response({"ok": True})

    def app(self) -> web.Application:
        """The aiohttp application."""
        app = web.Application(client_max_size=64 * 1024 * 1024)
        app.router.add_post("/v1/chat/completions", self.chat)
        app.router.add_post("/chat/completions", self.chat)
        app.router.add_get("/stats", self.stats)
        app.router.add_get("/requests", self.requests_seen)
        add_batch_routes(app, self)  # before the generateContent route, which would take them
        add_protocol_routes(app, self)
        app.router.add_post("/phase", self.set_phase)
        app.router.add_post("/config", self.set_config)
        return app


async def serve(
    config: dict[str, Any], port: int = 0, on_ready: Callable[[int], None] | None = None
) -> None:
    """Serve forever on 127.0.0.1; call ``on_ready(port)`` once listening."""
    runner = web.AppRunner(FakeOpenAI(config).app(), access_log=None)
    await runner.setup()
    site = web.TCPSite(runner, "127.0.0.1", port, backlog=1024)
    await site.start()
    if on_ready is not None:
        on_ready(runner.addresses[0][1])  # the port the system chose for port 0
    await asyncio.Event().wait()


def main(argv: list[str] | None = None) -> None:
    """Command line: ``--port``, ``--data``, ``--latency``, ``--config FILE`` (fault plan)."""
    parser = argparse.ArgumentParser(prog="python -m bpb_testing.fakeserver")
    parser.add_argument("--port", type=int, default=0)
    parser.add_argument("--data", default=None)
    parser.add_argument("--latency", type=float, default=0.0)
    parser.add_argument("--config", default=None)
    args = parser.parse_args(argv)
    config: dict[str, Any] = {}
    if args.config:
        config = json.loads(Path(args.config).read_text(encoding="utf-8"))
    config.setdefault("data", args.data)
    config.setdefault("latency", args.latency)

    def ready(port: int) -> None:
        sys.stdout.write(f"PORT {port}\n")
        sys.stdout.flush()

    asyncio.run(serve(config, args.port, ready))


if __name__ == "__main__":
    main()
