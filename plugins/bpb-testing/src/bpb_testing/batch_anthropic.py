"""Anthropic's Message Batches API on the fake server, in Anthropic's documented shapes.

``POST /v1/messages/batches`` (``requests``: ``custom_id`` and Messages ``params``),
``GET /v1/messages/batches/{id}``, ``GET /v1/messages/batches/{id}/results`` (JSON lines, once
the batch has ended), ``POST /v1/messages/batches/{id}/cancel``, ``GET /v1/messages/batches``
(``limit``, ``after_id``, ``before_id``; newest first) and ``DELETE /v1/messages/batches/{id}``.

``processing_status`` is ``in_progress``, ``canceling`` or ``ended``; ``request_counts`` keeps
every request ``processing`` until the batch ends, then counts ``succeeded``, ``errored``,
``canceled`` and ``expired``, the result ``type`` of each line. As the real API does, the
server refuses (400) a batch with no requests, a ``custom_id`` that is not 1-64 characters of
``[a-zA-Z0-9_-]`` or is repeated, a request without ``params``, and (413) more than 100,000
requests or a body over 256 MB; the ``params`` themselves are checked when the request is
processed (:func:`bpb_testing.rules.anthropic_rejection`), an invalid one ending ``errored``.
"""

from __future__ import annotations

import json
import re
from datetime import UTC, datetime
from typing import Any

from aiohttp import web

from bpb_testing.batches import BatchStore, Entry, Job, created

_CUSTOM_ID = re.compile(r"^[a-zA-Z0-9_-]{1,64}$")
_ENDED = {"expired": "expired", "cancelled": "canceled"}


def rfc3339(seconds: float | None) -> str | None:
    """A timestamp as the API writes it."""
    if seconds is None:
        return None
    return datetime.fromtimestamp(seconds, UTC).isoformat().replace("+00:00", "Z")


def error(status: int, kind: str, message: str) -> web.Response:
    """Anthropic's error body."""
    body = {"type": "error", "error": {"type": kind, "message": message}}
    return web.json_response(body, status=status)


def _result(entry: Entry, outcome: str | None) -> dict[str, Any]:
    if entry.result is None:
        return {"type": _ENDED.get(outcome or "", "expired")}
    if entry.ok:
        return {"type": "succeeded", "message": entry.result["body"]}
    return {"type": "errored", "error": {**entry.result["error"], "request_id": None}}


def batch_object(job: Job, base: str) -> dict[str, Any]:
    """The MessageBatch object of ``job``."""
    ended = job.outcome is not None
    counts = {"processing": len(job.entries), "succeeded": 0, "errored": 0, "canceled": 0,
              "expired": 0}  # fmt: skip
    if ended:
        counts["processing"] = 0
        for entry in job.entries:
            counts[_result(entry, job.outcome)["type"]] += 1
    status = "ended" if ended else ("canceling" if job.cancel_at is not None else "in_progress")
    return {
        "id": job.id,
        "type": "message_batch",
        "processing_status": status,
        "request_counts": counts,
        "ended_at": rfc3339(job.ended),
        "created_at": rfc3339(job.created),
        "expires_at": rfc3339(job.created + 86400),
        "archived_at": None,
        "cancel_initiated_at": rfc3339(job.cancel_at),
        "results_url": f"{base}/v1/messages/batches/{job.id}/results" if ended else None,
    }


def _requests_error(store: BatchStore, requests: Any, size: int) -> web.Response | None:
    if size > store.limits["anthropic_bytes"]:
        return error(
            413, "request_too_large", "Request exceeds the maximum allowed number of bytes."
        )
    if not isinstance(requests, list) or not requests:
        return error(400, "invalid_request_error", "requests: List should have at least 1 item")
    if len(requests) > store.limits["anthropic_requests"]:
        limit = store.limits["anthropic_requests"]
        return error(413, "request_too_large", f"A Message Batch holds at most {limit} requests.")
    seen: set[str] = set()
    for number, item in enumerate(requests):
        custom_id = item.get("custom_id") if isinstance(item, dict) else None
        if not isinstance(custom_id, str) or not _CUSTOM_ID.match(custom_id):
            return error(
                400,
                "invalid_request_error",
                f"requests.{number}.custom_id: String should match pattern "
                "'^[a-zA-Z0-9_-]{1,64}$'",
            )
        if custom_id in seen:
            return error(
                400,
                "invalid_request_error",
                f"requests.{number}.custom_id: Duplicate custom_id '{custom_id}'",
            )
        seen.add(custom_id)
        if not isinstance(item.get("params"), dict):
            return error(400, "invalid_request_error", f"requests.{number}.params: Field required")
    return None


def add_routes(app: web.Application, store: BatchStore) -> None:
    """Route the Message Batches API to ``store``."""

    def base(request: web.Request) -> str:
        return f"{request.scheme}://{request.host}"

    async def create(request: web.Request) -> web.StreamResponse:
        raw = await request.read()
        try:
            body = json.loads(raw)
        except json.JSONDecodeError:
            return error(400, "invalid_request_error", "The request body is not valid JSON.")
        requests = body.get("requests") if isinstance(body, dict) else None
        problem = _requests_error(store, requests, len(raw))
        if problem is not None:
            return problem
        assert isinstance(requests, list)
        entries = [Entry(r["custom_id"], "anthropic", r["params"]) for r in requests]
        job = store.add_job("anthropic", "msgbatch_fake", entries)
        store.advance(job)
        return await created(request, job, batch_object(job, base(request)))

    def find(request: web.Request) -> Job | None:
        return store.job("anthropic", request.match_info["batch_id"])

    def missing(request: web.Request) -> web.Response:
        return error(404, "not_found_error", f"No batch '{request.match_info['batch_id']}'.")

    async def retrieve(request: web.Request) -> web.Response:
        job = find(request)
        return (
            missing(request) if job is None else web.json_response(batch_object(job, base(request)))
        )

    async def results(request: web.Request) -> web.Response:
        job = find(request)
        if job is None:
            return missing(request)
        if job.outcome is None:
            return error(
                400,
                "invalid_request_error",
                f"Message Batch {job.id} has not yet ended; its results are not available.",
            )
        lines = [
            json.dumps({"custom_id": e.custom_id, "result": _result(e, job.outcome)})
            for e in job.entries
        ]
        return web.Response(
            body=("\n".join(lines) + "\n").encode(), content_type="application/x-jsonl"
        )

    async def cancel(request: web.Request) -> web.Response:
        job = find(request)
        if job is None:
            return missing(request)
        store.cancel(job)
        return web.json_response(batch_object(job, base(request)))

    async def delete(request: web.Request) -> web.Response:
        job = find(request)
        if job is None:
            return missing(request)
        if job.outcome is None:
            return error(
                400,
                "invalid_request_error",
                "A Message Batch must end before it can be deleted; cancel it first.",
            )
        del store.jobs[job.id]
        return web.json_response({"id": job.id, "type": "message_batch_deleted"})

    async def listing(request: web.Request) -> web.Response:
        jobs = store.listed("anthropic")
        ids = [j.id for j in jobs]
        after, before = request.query.get("after_id"), request.query.get("before_id")
        if after in ids:
            jobs = jobs[ids.index(after) + 1 :]
        elif before in ids:
            jobs = jobs[: ids.index(before)]
        limit = int(request.query.get("limit", "20"))
        page = [batch_object(j, base(request)) for j in jobs[:limit]]
        return web.json_response(
            {
                "data": page,
                "has_more": len(jobs) > limit,
                "first_id": page[0]["id"] if page else None,
                "last_id": page[-1]["id"] if page else None,
            }
        )

    app.router.add_post("/v1/messages/batches", create)
    app.router.add_get("/v1/messages/batches", listing)
    app.router.add_get("/v1/messages/batches/{batch_id}", retrieve)
    app.router.add_delete("/v1/messages/batches/{batch_id}", delete)
    app.router.add_get("/v1/messages/batches/{batch_id}/results", results)
    app.router.add_post("/v1/messages/batches/{batch_id}/cancel", cancel)
