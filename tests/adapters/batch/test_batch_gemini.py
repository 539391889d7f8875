"""Gemini's batch mode against the fake server over real HTTP on 127.0.0.1, through the official
``google-genai`` SDK; the pinned litellm has no Gemini batch call (``create_batch`` and the
others refuse ``custom_llm_provider="gemini"``; only ``create_file`` uploads to Gemini's Files
API).

Inline requests answer in ``dest.inlined_responses``; a JSON-lines input file uploaded with
``files.upload`` answers in a responses file read with ``files.download``.
"""

from __future__ import annotations

import io
import json
from collections.abc import Callable
from contextlib import AbstractContextManager
from typing import Any

import pytest

genai = pytest.importorskip("google.genai")
litellm = pytest.importorskip("litellm")

N = 20
MODEL = "gemini-3-flash-preview"
Start = Callable[..., AbstractContextManager[Any]]


def _client(server: Any) -> Any:
    from google.genai import types

    options = types.HttpOptions(
        base_url=server.url, retry_options=types.HttpRetryOptions(attempts=1)
    )
    return genai.Client(api_key="AIza-bpb-test", http_options=options)


def _inline(requests: Any, n: int = N) -> list[dict[str, Any]]:
    out = []
    for i in range(n):
        part = {"inline_data": {"mime_type": "image/png", "data": requests.png}}
        contents = [{"role": "user", "parts": [{"text": requests.prompt(i)}, part]}]
        out.append({"contents": contents, "metadata": {"key": f"run1-{i:03d}"}})
    return out


def _text(response: Any) -> Any:
    return json.loads(next(p.text for p in response.candidates[0].content.parts if not p.thought))


def test_inline_round_trip(batch_server: Start, requests: Any) -> None:
    """20 inline requests with an image: pending, running, succeeded; each answer with its
    request's metadata; listed by display name; billed once each."""
    with batch_server(batch={"validating": 30, "in_progress": 600}) as server:
        client = _client(server)
        job = client.batches.create(
            model=MODEL, src=_inline(requests), config={"display_name": "bpb-run1-0"}
        )
        assert job.name.startswith("batches/") and job.state == "JOB_STATE_PENDING"
        server.advance(330)
        job = client.batches.get(name=job.name)
        assert job.state == "JOB_STATE_RUNNING" and job.dest is None
        server.advance(300)
        job = client.batches.get(name=job.name)
        assert job.state == "JOB_STATE_SUCCEEDED" and job.display_name == "bpb-run1-0"
        got = {r.metadata["key"]: _text(r.response) for r in job.dest.inlined_responses}
        assert got == {f"run1-{i:03d}": requests.answer(i) for i in range(N)}
        assert [(j.name, j.display_name) for j in client.batches.list()] == [
            (job.name, "bpb-run1-0")
        ]
        assert server.paid() == {f"run1-{i:03d}": 1 for i in range(N)}
        assert server.server.stats()["images"] == N


def test_file_round_trip_with_failed_requests(batch_server: Start, requests: Any) -> None:
    """A JSON-lines input file: the responses file has a ``response`` or, for an injected
    fault, Google's ``error`` per key."""
    plan = ["ok", "503", "ok", "429"] + ["ok"] * N
    with batch_server(faults={"unknown/unknown": plan}) as server:
        client = _client(server)
        lines = [
            json.dumps({"key": f"run1-{i:03d}", "request": requests.gemini(i)}) for i in range(N)
        ]
        upload = client.files.upload(
            file=io.BytesIO("\n".join(lines).encode()),
            config={"mime_type": "application/jsonl", "display_name": "in"},
        )
        job = client.batches.create(
            model=MODEL, src=upload.name, config={"display_name": "bpb-run1-1"}
        )
        job = client.batches.get(name=job.name)
        assert job.state == "JOB_STATE_SUCCEEDED" and job.dest.file_name
        out = [
            json.loads(x)
            for x in client.files.download(file=job.dest.file_name).decode().splitlines()
        ]
        errors = {x["key"]: x["error"]["status"] for x in out if "error" in x}
        assert errors == {"run1-001": "UNAVAILABLE", "run1-003": "RESOURCE_EXHAUSTED"}
        assert len([x for x in out if "response" in x]) == N - 2
        assert len(server.paid()) == N - 2


def test_expired_and_cancelled_jobs(batch_server: Start, requests: Any) -> None:
    """A job that falls behind expires after 48 h with only its answered requests in the
    output; a cancelled one ends cancelled with the answers so far."""
    with batch_server(batch={"plan": [{"stall_after": 7}, {}], "in_progress": 100}) as server:
        client = _client(server)
        slow = client.batches.create(
            model=MODEL, src=_inline(requests), config={"display_name": "a"}
        )
        server.advance(86400)
        assert client.batches.get(name=slow.name).state == "JOB_STATE_RUNNING"
        server.advance(86400)
        slow = client.batches.get(name=slow.name)
        assert slow.state == "JOB_STATE_EXPIRED" and len(slow.dest.inlined_responses) == 7
        job = client.batches.create(
            model=MODEL, src=_inline(requests), config={"display_name": "b"}
        )
        server.advance(50)
        client.batches.cancel(name=job.name)
        job = client.batches.get(name=job.name)
        assert job.state == "JOB_STATE_CANCELLED" and len(job.dest.inlined_responses) == N // 2
        assert sum(server.paid().values()) == 7 + N // 2


def test_refused_and_litellm_reach(batch_server: Start, requests: Any) -> None:
    """An unknown input file (404) and inline requests over the size limit (400) are refused;
    litellm's batch calls refuse Gemini."""
    with batch_server(batch={"gemini_inline_bytes": 2000}) as server:
        client = _client(server)
        with pytest.raises(genai.errors.ClientError, match="NOT_FOUND"):
            client.batches.create(model=MODEL, src="files/nothing", config={"display_name": "x"})
        with pytest.raises(genai.errors.ClientError, match="payload size"):
            client.batches.create(model=MODEL, src=_inline(requests), config={"display_name": "x"})
        kw = {"custom_llm_provider": "gemini", "api_base": server.url, "api_key": "AIza-x"}
        with pytest.raises(Exception, match="support"):
            litellm.create_batch(
                completion_window="24h",
                endpoint="/v1/chat/completions",
                input_file_id="files/x",
                **kw,
            )
        with pytest.raises(Exception, match="support"):
            litellm.retrieve_batch(batch_id="batches/x", **kw)
        assert server.stats()["jobs"] == {}


def test_failed_job(batch_server: Start, requests: Any) -> None:
    """A job the provider fails whole (``fail`` in the job plan): ``JOB_STATE_FAILED``, no
    output, nothing billed."""
    with batch_server(
        batch={"plan": [{"fail": "Internal error while processing the batch."}]}
    ) as server:
        client = _client(server)
        job = client.batches.create(
            model=MODEL, src=_inline(requests, n=3), config={"display_name": "f"}
        )
        job = client.batches.get(name=job.name)
        assert job.state == "JOB_STATE_FAILED" and job.dest is None
        assert server.paid() == {}
