"""The Gemini API's batch mode and Files API on the fake server, in Google's documented REST
shapes (``v1beta``).

- ``POST /v1beta/models/{model}:batchGenerateContent`` with ``{"batch": {"displayName",
  "inputConfig": {"requests": {"requests": [{"request", "metadata"}]}}}}`` (inline) or
  ``"inputConfig": {"fileName": "files/..."}`` (a JSON-lines file of ``{"key", "request"}``): a
  long-running Operation named ``batches/{id}`` whose ``metadata`` is the GenerateContentBatch
  (``state``, ``batchStats``, ``output``);
- ``GET /v1beta/batches/{id}``, ``GET /v1beta/batches`` (``pageSize``, ``pageToken``),
  ``POST /v1beta/batches/{id}:cancel``, ``DELETE /v1beta/batches/{id}``;
- the resumable upload ``POST /upload/v1beta/files`` (``X-Goog-Upload-Command: start``, then
  ``upload, finalize`` to the ``X-Goog-Upload-URL`` it returns), ``GET /v1beta/files/{id}`` and
  the download ``GET /download/v1beta/files/{id}:download?alt=media``.

``state`` moves ``BATCH_STATE_PENDING``, ``BATCH_STATE_RUNNING``, then ``BATCH_STATE_SUCCEEDED``,
``BATCH_STATE_FAILED``, ``BATCH_STATE_CANCELLED`` or ``BATCH_STATE_EXPIRED`` (48 h). An inline
batch's answers are ``output.inlinedResponses.inlinedResponses`` in request order (each
``response`` or ``error``, with the request's ``metadata``); a file batch's are the
``output.responsesFile`` file, one ``{"key", "response"}`` or ``{"key", "error"}`` line per
answered request. Requests an expired or cancelled batch did not answer have no output. The
server refuses (400 ``INVALID_ARGUMENT``) a body without ``batch.inputConfig``, with both or
neither source, an inline request without ``request``, inline requests over 20 MB and a file
over 2 GB, and (404) an unknown input file.
"""

from __future__ import annotations

import json
from typing import Any

from aiohttp import web

from bpb_testing.batch_anthropic import rfc3339
from bpb_testing.batches import BatchStore, Entry, Handler, Job, created

_STATES = {None: "BATCH_STATE_RUNNING", "completed": "BATCH_STATE_SUCCEEDED",
           "failed": "BATCH_STATE_FAILED", "cancelled": "BATCH_STATE_CANCELLED",
           "expired": "BATCH_STATE_EXPIRED"}  # fmt: skip
_TYPE = "type.googleapis.com/google.ai.generativelanguage.v1main."


def error(status: int, kind: str, message: str) -> web.Response:
    """Google's error body."""
    return web.json_response(
        {"error": {"code": status, "message": message, "status": kind}}, status=status
    )


def _file(store: BatchStore, content: bytes, display: str, mime: str) -> dict[str, Any]:
    file_id = store.new_id("fakefile")
    stamp = rfc3339(store.now())
    file = {
        "name": f"files/{file_id}",
        "displayName": display,
        "mimeType": mime,
        "sizeBytes": str(len(content)),
        "createTime": stamp,
        "updateTime": stamp,
        "uri": f"files/{file_id}",
        "state": "ACTIVE",
        "source": "UPLOADED",
        "content": content,
        "provider": "gemini",
    }
    store.files[f"files/{file_id}"] = file
    return file


def _public(file: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in file.items() if k not in ("content", "provider")}


def _reply(entry: Entry) -> dict[str, Any]:
    assert entry.result is not None
    if entry.ok:
        return {"response": entry.result["body"]}
    return {"error": entry.result["error"]["error"]}


def _output(store: BatchStore, job: Job) -> dict[str, Any] | None:
    """The batch's output once it has ended: inline answers, or the responses file."""
    if job.outcome in (None, "failed"):
        return None
    answered = [e for e in job.entries if e.result is not None]
    if job.info["inline"]:
        items = [{**_reply(e), "metadata": e.info} for e in answered]
        return {"inlinedResponses": {"inlinedResponses": items}}
    if "responses_file" not in job.info:
        lines = [json.dumps({"key": e.custom_id, **_reply(e)}) for e in answered]
        content = ("\n".join(lines) + "\n").encode() if lines else b""
        job.info["responses_file"] = _file(store, content, f"{job.id}-output", "application/jsonl")[
            "name"
        ]
    return {"responsesFile": job.info["responses_file"]}


def operation(store: BatchStore, job: Job) -> dict[str, Any]:
    """The Operation of ``job``: its GenerateContentBatch in ``metadata``."""
    counts = job.counts()
    status = job.status()
    state = "BATCH_STATE_PENDING" if status == "validating" else _STATES[job.outcome]
    batch: dict[str, Any] = {
        "@type": _TYPE + "GenerateContentBatch",
        "name": f"batches/{job.id}",
        "model": job.info["model"],
        "displayName": job.info["display_name"],
        "createTime": rfc3339(job.created),
        "updateTime": rfc3339(job.ended or store.now()),
        "batchStats": {
            "requestCount": str(counts["total"]),
            "successfulRequestCount": str(counts["ok"]),
            "failedRequestCount": str(counts["error"]),
            "pendingRequestCount": str(counts["pending"]),
        },
        "state": state,
    }
    if job.ended is not None:
        batch["endTime"] = rfc3339(job.ended)
    output = _output(store, job)
    op: dict[str, Any] = {
        "name": f"batches/{job.id}",
        "metadata": batch,
        "done": job.outcome is not None,
    }
    if output is not None:
        batch["output"] = output
        op["response"] = {"@type": _TYPE + "GenerateContentBatchOutput", **output}
    if job.outcome == "failed":
        message = "; ".join(e["message"] for e in job.errors) or "The batch failed."
        op["error"] = {"code": 3, "message": message}
    return op


def _entries(store: BatchStore, config: dict[str, Any], size: int) -> list[Entry] | web.Response:
    """The requests of ``inputConfig``, or the error reply."""
    inline, file_name = config.get("requests"), config.get("fileName")
    if (inline is None) == (file_name is None):
        return error(
            400,
            "INVALID_ARGUMENT",
            "batch.input_config: exactly one of requests or file_name must be set.",
        )
    entries: list[Entry] = []
    if inline is not None:
        if size > store.limits["gemini_inline_bytes"]:
            return error(
                400,
                "INVALID_ARGUMENT",
                "Request payload size exceeds the limit for inline batch requests; use a file.",
            )
        for number, item in enumerate(inline.get("requests") or []):
            if not isinstance(item, dict) or not isinstance(item.get("request"), dict):
                return error(
                    400,
                    "INVALID_ARGUMENT",
                    f"batch.input_config.requests.requests[{number}].request: required field "
                    "is missing.",
                )
            metadata = item.get("metadata") or {}
            entry = Entry(str(metadata.get("key", f"#{number}")), "gemini", item["request"])
            entry.info = metadata
            entries.append(entry)
        if not entries:
            return error(
                400,
                "INVALID_ARGUMENT",
                "batch.input_config.requests: at least one request is required.",
            )
        return entries
    file = store.files.get(str(file_name))
    if file is None or file["provider"] != "gemini":
        return error(404, "NOT_FOUND", f"File {file_name} not found.")
    for number, raw in enumerate(file["content"].decode("utf-8", "replace").splitlines()):
        if not raw.strip():
            continue
        try:
            line = json.loads(raw)
        except json.JSONDecodeError:
            return error(400, "INVALID_ARGUMENT", f"{file_name} line {number + 1}: not valid JSON.")
        if not isinstance(line, dict) or not isinstance(line.get("request"), dict):
            return error(
                400, "INVALID_ARGUMENT", f"{file_name} line {number + 1}: request is required."
            )
        entries.append(Entry(str(line.get("key", f"#{number}")), "gemini", line["request"]))
    return entries


def add_routes(app: web.Application, store: BatchStore) -> dict[str, Handler]:
    """Route Gemini's batch mode and Files API to ``store``; give the handlers of
    ``GET /v1/batches`` and ``GET /v1/batches/{id}``."""

    async def create(request: web.Request) -> web.StreamResponse:
        raw = await request.read()
        body = json.loads(raw)
        batch = body.get("batch") if isinstance(body, dict) else None
        if not isinstance(batch, dict) or not isinstance(batch.get("inputConfig"), dict):
            return error(400, "INVALID_ARGUMENT", "batch.input_config: required field is missing.")
        entries = _entries(store, batch["inputConfig"], len(raw))
        if isinstance(entries, web.Response):
            return entries
        model = f"models/{request.match_info['model']}"
        job = store.add_job(
            "gemini",
            "fakebatch",
            entries,
            model=model,
            display_name=batch.get("displayName", ""),
            inline="requests" in batch["inputConfig"],
        )
        return await created(request, job, operation(store, job))

    def find(request: web.Request) -> Job | None:
        return store.job("gemini", request.match_info["batch_id"])

    def missing(request: web.Request) -> web.Response:
        return error(404, "NOT_FOUND", f"Batch batches/{request.match_info['batch_id']} not found.")

    async def retrieve(request: web.Request) -> web.Response:
        job = find(request)
        return missing(request) if job is None else web.json_response(operation(store, job))

    async def cancel(request: web.Request) -> web.Response:
        job = find(request)
        if job is None:
            return missing(request)
        if job.outcome is not None:
            return error(400, "FAILED_PRECONDITION", f"Batch batches/{job.id} has already ended.")
        store.cancel(job)
        return web.json_response({})

    async def delete(request: web.Request) -> web.Response:
        job = find(request)
        if job is None:
            return missing(request)
        del store.jobs[job.id]
        return web.json_response({})

    async def listing(request: web.Request) -> web.Response:
        jobs = store.listed("gemini")
        start = int(request.query.get("pageToken") or 0)
        size = int(request.query.get("pageSize") or 50)
        page = jobs[start : start + size]
        reply: dict[str, Any] = {"operations": [operation(store, j) for j in page]}
        if start + size < len(jobs):
            reply["nextPageToken"] = str(start + size)
        return web.json_response(reply)

    uploads: dict[str, dict[str, Any]] = {}

    async def upload(request: web.Request) -> web.Response:
        command = request.headers.get("X-Goog-Upload-Command", "")
        if command == "start":
            size = int(request.headers.get("X-Goog-Upload-Header-Content-Length", "0"))
            if size > store.limits["gemini_file_bytes"]:
                return error(400, "INVALID_ARGUMENT", "File size exceeds the 2 GB limit.")
            body = await request.json() if request.can_read_body else {}
            upload_id = store.new_id("upload")
            uploads[upload_id] = {
                "meta": (body or {}).get("file") or {},
                "mime": request.headers.get(
                    "X-Goog-Upload-Header-Content-Type", "application/octet-stream"
                ),
                "data": b"",
            }
            url = f"{request.scheme}://{request.host}{request.path}?upload_id={upload_id}"
            return web.json_response(
                {}, headers={"X-Goog-Upload-URL": url, "X-Goog-Upload-Status": "active"}
            )
        state = uploads.get(request.query.get("upload_id", ""))
        if state is None:
            return error(404, "NOT_FOUND", "Unknown upload.")
        state["data"] += await request.read()
        if len(state["data"]) > store.limits["gemini_file_bytes"]:
            return error(400, "INVALID_ARGUMENT", "File size exceeds the 2 GB limit.")
        if "finalize" not in command:
            return web.json_response({}, headers={"X-Goog-Upload-Status": "active"})
        meta = state["meta"]
        file = _file(
            store,
            state["data"],
            meta.get("displayName") or meta.get("display_name") or "",
            meta.get("mimeType") or state["mime"],
        )
        return web.json_response({"file": _public(file)}, headers={"X-Goog-Upload-Status": "final"})

    async def file_get(request: web.Request) -> web.Response:
        file = store.files.get(f"files/{request.match_info['file_id']}")
        if file is None or file["provider"] != "gemini":
            return error(404, "NOT_FOUND", "File not found.")
        return web.json_response(_public(file))

    async def download(request: web.Request) -> web.Response:
        file = store.files.get(f"files/{request.match_info['file_id']}")
        if file is None or file["provider"] != "gemini":
            return error(404, "NOT_FOUND", "File not found.")
        return web.Response(body=file["content"], content_type="application/octet-stream")

    # The REST reference says v1beta; google-genai 3.x calls v1, whose GET /v1/batches and
    # /v1/batches/{id} OpenAI's Batch API shares (bpb_testing.batches routes those by key header)
    for version in ("v1beta", "v1"):
        app.router.add_post(f"/{version}/models/{{model:[^/:]+}}:batchGenerateContent", create)
        app.router.add_post(f"/{version}/batches/{{batch_id:[^/:]+}}:cancel", cancel)
        app.router.add_delete(f"/{version}/batches/{{batch_id:[^/:]+}}", delete)
        app.router.add_post(f"/upload/{version}/files", upload)
        for prefix in (f"/download/{version}", f"/{version}"):
            app.router.add_get(prefix + "/files/{file_id:[^/:]+}:download", download)
    app.router.add_get("/v1beta/batches", listing)
    app.router.add_get("/v1beta/batches/{batch_id:[^/:]+}", retrieve)
    app.router.add_get("/v1beta/files/{file_id:[^/:]+}", file_get)
    return {"list": listing, "retrieve": retrieve}
