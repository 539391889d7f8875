"""OpenAI's Files API and Batch API on the fake server, in OpenAI's documented shapes.

- ``POST /v1/files`` (multipart ``file`` and ``purpose``), ``GET /v1/files/{id}``,
  ``GET /v1/files/{id}/content``, ``DELETE /v1/files/{id}``;
- ``POST /v1/batches`` (``input_file_id``, ``endpoint`` ``/v1/chat/completions`` or
  ``/v1/responses``, ``completion_window`` ``24h``, ``metadata``), ``GET /v1/batches/{id}``,
  ``POST /v1/batches/{id}/cancel``, ``GET /v1/batches`` (``limit``, ``after``; newest first).

A batch is ``validating``, then ``in_progress``, ``finalizing`` and ``completed``; or
``failed`` (its input did not validate: ``errors.data`` names each bad line), ``expired``
(the 24 h window ended) or ``cancelling`` then ``cancelled``. When it ends its answers are in the
``output_file_id`` file and its errors in the ``error_file_id`` file, one JSON line per request
(``{"id", "custom_id", "response": {"status_code", "request_id", "body"}, "error"}``); a request
left unanswered by expiry or cancellation is an error line with ``response: null`` and ``error``
``batch_expired`` or ``batch_cancelled``. Like the real API the server rejects a request with no
or a bad ``purpose``, a file over the size limit, an unknown file, an unsupported endpoint or
window, and metadata past 16 pairs (64-character keys, 512-character values); the input file is
checked when the batch validates: a line that is not JSON, a line missing ``custom_id``,
``method``, ``url`` or ``body``, a ``url`` other than the batch's endpoint, a repeated
``custom_id``, a model other than the first line's, more than 50,000 requests or more than
200 MB fail the batch.
"""

from __future__ import annotations

import json
from typing import Any

from aiohttp import web

from bpb_testing.batches import BatchStore, Entry, Handler, Job, created

ENDPOINTS = {"/v1/chat/completions": "openai-chat", "/v1/responses": "openai-responses"}
PURPOSES = ("assistants", "batch", "fine-tune", "vision", "user_data", "evals")
_META_PAIRS, _META_KEY, _META_VALUE = 16, 64, 512
_UNANSWERED = {
    "expired": ("batch_expired", "This request could not be executed before the completion "
                "window expired."),
    "cancelled": ("batch_cancelled", "This request was not executed because the batch was "
                  "cancelled."),
}  # fmt: skip


def error(
    status: int, message: str, param: str | None = None, code: str | None = None
) -> web.Response:
    """OpenAI's error body."""
    body = {"message": message, "type": "invalid_request_error", "param": param, "code": code}
    return web.json_response({"error": body}, status=status)


def _file_object(file: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in file.items() if k != "content"}


def _add_file(store: BatchStore, content: bytes, filename: str, purpose: str) -> dict[str, Any]:
    file_id = store.new_id("file-fake")
    file = {
        "id": file_id,
        "object": "file",
        "bytes": len(content),
        "created_at": int(store.now()),
        "filename": filename,
        "purpose": purpose,
        "status": "processed",
        "expires_at": None,
        "status_details": None,
        "content": content,
        "provider": "openai",
    }
    store.files[file_id] = file
    return file


def _parse_lines(
    store: BatchStore, content: bytes, endpoint: str
) -> tuple[list[Entry], list[dict[str, Any]]]:
    """The requests of an input file and what is wrong with it (``errors.data``)."""
    entries: list[Entry] = []
    errors: list[dict[str, Any]] = []
    seen: set[str] = set()
    model: str | None = None

    def bad(line: int, code: str, message: str, param: str | None = None) -> None:
        errors.append({"code": code, "message": message, "param": param, "line": line})

    if len(content) > store.limits["openai_batch_bytes"]:
        bad(0, "file_too_large", "The input file exceeds the maximum size for a batch.")
    for number, raw in enumerate(content.decode("utf-8", "replace").splitlines(), 1):
        if not raw.strip():
            continue
        try:
            line = json.loads(raw)
        except json.JSONDecodeError:
            bad(number, "invalid_json_line", "This line is not parseable as valid JSON.")
            continue
        if not isinstance(line, dict):
            bad(number, "invalid_json_line", "This line is not a JSON object.")
            continue
        missing = [k for k in ("custom_id", "method", "url", "body") if k not in line]
        if missing:
            bad(
                number,
                "missing_required_parameter",
                f"Missing required parameter: '{missing[0]}'.",
                missing[0],
            )
            continue
        if line["method"] != "POST" or line["url"] != endpoint:
            bad(
                number,
                "mismatched_endpoint",
                f"The url must be {endpoint}, the batch's endpoint.",
                "url",
            )
            continue
        custom_id = str(line["custom_id"])
        if custom_id in seen:
            bad(
                number,
                "duplicate_custom_id",
                f"The custom_id '{custom_id}' is not unique in the batch.",
                "custom_id",
            )
            continue
        seen.add(custom_id)
        body = line["body"]
        if not isinstance(body, dict) or "model" not in body:
            bad(
                number,
                "missing_required_parameter",
                "Missing required parameter: 'body.model'.",
                "body.model",
            )
            continue
        if model is None:
            model = str(body["model"])
        elif body["model"] != model:
            bad(
                number,
                "mismatched_model",
                f"All requests in a batch must use one model; this line uses "
                f"'{body['model']}', the first '{model}'.",
                "body.model",
            )
            continue
        entries.append(Entry(custom_id, ENDPOINTS[endpoint], body))
    if len(entries) > store.limits["openai_requests"]:
        bad(
            0,
            "too_many_requests",
            f"A batch holds at most {store.limits['openai_requests']} requests.",
        )
    if not entries and not errors:
        bad(0, "empty_file", "The input file has no requests.")
    return entries, errors


def _result_line(store: BatchStore, entry: Entry, outcome: str | None) -> dict[str, Any]:
    line: dict[str, Any] = {"id": store.new_id("batch_req_fake"), "custom_id": entry.custom_id}
    if entry.result is None:
        code, message = _UNANSWERED.get(outcome or "", _UNANSWERED["expired"])
        return {**line, "response": None, "error": {"code": code, "message": message}}
    body = entry.result.get("body", entry.result.get("error"))
    response = {
        "status_code": entry.result["status"],
        "request_id": f"req_fake_{entry.custom_id}",
        "body": body,
    }
    return {**line, "response": response, "error": None}


def _write_results(store: BatchStore, job: Job) -> None:
    """On its end, the job's output and error files (each only when it has a line)."""
    if job.outcome in (None, "failed") or "output_file_id" in job.info:
        return
    out: list[str] = []
    err: list[str] = []
    for entry in job.entries:
        (out if entry.ok else err).append(json.dumps(_result_line(store, entry, job.outcome)))
    for key, lines, name in (("output_file_id", out, "output"), ("error_file_id", err, "error")):
        job.info[key] = None
        if lines:
            content = ("\n".join(lines) + "\n").encode()
            job.info[key] = _add_file(
                store, content, f"batch_{job.id}_{name}.jsonl", "batch_output"
            )["id"]


def batch_object(store: BatchStore, job: Job) -> dict[str, Any]:
    """The Batch object of ``job``."""
    _write_results(store, job)
    counts = job.counts()
    unanswered = counts["pending"] if job.outcome is not None else 0
    status = job.status()
    ended = int(job.ended) if job.ended is not None else None
    stamp = {
        f"{name}_at": ended if job.outcome == name else None
        for name in ("completed", "failed", "expired", "cancelled")
    }
    errors = {"object": "list", "data": job.errors} if job.errors else None
    return {
        "id": job.id,
        "object": "batch",
        "endpoint": job.info["endpoint"],
        "model": job.info.get("model"),
        "errors": errors,
        "input_file_id": job.info["input_file_id"],
        "completion_window": "24h",
        "status": status,
        "output_file_id": job.info.get("output_file_id"),
        "error_file_id": job.info.get("error_file_id"),
        "created_at": int(job.created),
        "in_progress_at": int(job.started) if job.started is not None else None,
        "expires_at": int(job.created + 86400),
        "finalizing_at": int(job.finalizing) if job.finalizing is not None else None,
        "cancelling_at": int(job.cancel_at) if job.cancel_at is not None else None,
        **stamp,
        "request_counts": {
            "total": counts["total"],
            "completed": counts["ok"],
            "failed": counts["error"] + unanswered,
        },
        "metadata": job.info.get("metadata"),
    }


def _metadata_error(metadata: Any) -> str | None:
    if metadata is None:
        return None
    if not isinstance(metadata, dict) or len(metadata) > _META_PAIRS:
        return f"metadata: at most {_META_PAIRS} key-value pairs."
    for key, value in metadata.items():
        if len(str(key)) > _META_KEY or not isinstance(value, str) or len(value) > _META_VALUE:
            return (
                f"metadata: keys of at most {_META_KEY} and string values of at most "
                f"{_META_VALUE} characters."
            )
    return None


def add_routes(app: web.Application, store: BatchStore) -> dict[str, Handler]:
    """Route the Files and Batch APIs to ``store``; give the handlers of ``GET /v1/batches``
    and ``GET /v1/batches/{id}``."""

    async def upload(request: web.Request) -> web.Response:
        form = await request.post()
        purpose, file = form.get("purpose"), form.get("file")
        if not isinstance(purpose, str):
            return error(400, "Missing required parameter: 'purpose'.", "purpose")
        if purpose not in PURPOSES:
            return error(
                400,
                f"'{purpose}' is not one of {list(PURPOSES)} - 'purpose'",
                "purpose",
                "invalid_value",
            )
        if not isinstance(file, web.FileField):
            return error(400, "Missing required parameter: 'file'.", "file")
        content = file.file.read()
        if len(content) > store.limits["openai_file_bytes"]:
            return error(
                400,
                f"File is too large: at most {store.limits['openai_file_bytes']} bytes.",
                "file",
                "file_too_large",
            )
        return web.json_response(_file_object(_add_file(store, content, file.filename, purpose)))

    def find_file(request: web.Request) -> dict[str, Any] | None:
        file = store.files.get(request.match_info["file_id"])
        return file if file is not None and file["provider"] == "openai" else None

    async def file_get(request: web.Request) -> web.Response:
        file = find_file(request)
        if file is None:
            return error(404, f"No such File object: {request.match_info['file_id']}", "id")
        return web.json_response(_file_object(file))

    async def file_content(request: web.Request) -> web.Response:
        file = find_file(request)
        if file is None:
            return error(404, f"No such File object: {request.match_info['file_id']}", "id")
        return web.Response(body=file["content"], content_type="application/octet-stream")

    async def file_delete(request: web.Request) -> web.Response:
        file = find_file(request)
        if file is None:
            return error(404, f"No such File object: {request.match_info['file_id']}", "id")
        del store.files[file["id"]]
        return web.json_response({"id": file["id"], "object": "file", "deleted": True})

    async def create(request: web.Request) -> web.StreamResponse:
        body = await request.json()
        for key in ("input_file_id", "endpoint", "completion_window"):
            if key not in body:
                return error(400, f"Missing required parameter: '{key}'.", key)
        endpoint = body["endpoint"]
        if endpoint not in ENDPOINTS:
            return error(
                400,
                f"Invalid value for 'endpoint': {endpoint} is not supported here.",
                "endpoint",
                "invalid_value",
            )
        if body["completion_window"] != "24h":
            return error(
                400,
                "Invalid value for 'completion_window': only '24h' is supported.",
                "completion_window",
                "invalid_value",
            )
        problem = _metadata_error(body.get("metadata"))
        if problem is not None:
            return error(400, problem, "metadata", "invalid_value")
        file = store.files.get(body["input_file_id"])
        if file is None or file["provider"] != "openai":
            return error(404, f"No such File object: {body['input_file_id']}", "input_file_id")
        if file["purpose"] != "batch":
            return error(
                400,
                "The input file must be uploaded with purpose 'batch'.",
                "input_file_id",
                "invalid_value",
            )
        entries, errors = _parse_lines(store, file["content"], endpoint)
        model = entries[0].body.get("model") if entries else None
        job = store.add_job(
            "openai",
            "batch_fake",
            entries if not errors else [],
            endpoint=endpoint,
            input_file_id=file["id"],
            metadata=body.get("metadata"),
            model=model,
        )
        job.errors = errors
        return await created(request, job, batch_object(store, job))

    def find(request: web.Request) -> Job | None:
        return store.job("openai", request.match_info["batch_id"])

    async def retrieve(request: web.Request) -> web.Response:
        job = find(request)
        if job is None:
            return error(
                404, f"No batch found with id '{request.match_info['batch_id']}'.", "batch_id"
            )
        return web.json_response(batch_object(store, job))

    async def cancel(request: web.Request) -> web.Response:
        job = find(request)
        if job is None:
            return error(
                404, f"No batch found with id '{request.match_info['batch_id']}'.", "batch_id"
            )
        if job.outcome is not None:
            return error(
                409,
                f"Cannot cancel a batch with status '{job.outcome}'.",
                None,
                "batch_not_cancellable",
            )
        store.cancel(job)
        return web.json_response(batch_object(store, job))

    async def listing(request: web.Request) -> web.Response:
        jobs = store.listed("openai")
        after = request.query.get("after")
        if after is not None:
            ids = [j.id for j in jobs]
            jobs = jobs[ids.index(after) + 1 :] if after in ids else []
        limit = int(request.query.get("limit", "20"))
        page = [batch_object(store, j) for j in jobs[:limit]]
        return web.json_response(
            {
                "object": "list",
                "data": page,
                "first_id": page[0]["id"] if page else None,
                "last_id": page[-1]["id"] if page else None,
                "has_more": len(jobs) > limit,
            }
        )

    for prefix in ("/v1", ""):
        app.router.add_post(f"{prefix}/files", upload)
        app.router.add_get(f"{prefix}/files/{{file_id}}", file_get)
        app.router.add_delete(f"{prefix}/files/{{file_id}}", file_delete)
        app.router.add_get(f"{prefix}/files/{{file_id}}/content", file_content)
        app.router.add_post(f"{prefix}/batches", create)
        app.router.add_post(f"{prefix}/batches/{{batch_id}}/cancel", cancel)
    app.router.add_get("/batches", listing)
    app.router.add_get("/batches/{batch_id}", retrieve)
    return {"list": listing, "retrieve": retrieve}
