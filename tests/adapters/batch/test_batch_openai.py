"""OpenAI's Files and Batch APIs through the pinned litellm's public batch functions, against the
fake server's batch endpoints over real HTTP on 127.0.0.1.

litellm covers OpenAI whole: ``create_file`` (purpose ``batch``), ``create_batch`` (chat
completions and Responses, with metadata), ``retrieve_batch``, ``file_content`` (output and
error files), ``cancel_batch`` and ``list_batches``. The tests round-trip 20 requests with an
image, walk a batch through validating, in progress and completed on the server's clock, and
check an expired batch, a batch with failed requests, a cancelled one and the inputs the real
API refuses; every answer is billed once (counted at the server).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from contextlib import AbstractContextManager
from typing import Any

import pytest

litellm = pytest.importorskip("litellm")

N = 20


def _kw(server: Any) -> dict[str, Any]:
    return {
        "custom_llm_provider": "openai",
        "api_base": server.url + "/v1",
        "api_key": "sk-bpb-test",
    }


def _jsonl(lines: list[dict[str, Any]]) -> bytes:
    return ("\n".join(json.dumps(line) for line in lines) + "\n").encode()


def _lines(
    requests: Any, endpoint: str = "/v1/chat/completions", n: int = N
) -> list[dict[str, Any]]:
    make = requests.chat if endpoint == "/v1/chat/completions" else requests.responses
    return [
        {"custom_id": f"run1-{i:03d}", "method": "POST", "url": endpoint, "body": make(i)}
        for i in range(n)
    ]


def _submit(
    server: Any,
    lines: list[dict[str, Any]],
    endpoint: str = "/v1/chat/completions",
    metadata: dict[str, str] | None = None,
) -> Any:
    file = litellm.create_file(file=("batch.jsonl", _jsonl(lines)), purpose="batch", **_kw(server))
    return litellm.create_batch(
        completion_window="24h",
        endpoint=endpoint,
        input_file_id=file.id,
        metadata=metadata,
        **_kw(server),
    )


def _file(server: Any, file_id: str | None) -> dict[str, dict[str, Any]]:
    """A results file by custom_id."""
    if file_id is None:
        return {}
    content = litellm.file_content(file_id=file_id, **_kw(server)).content
    return {line["custom_id"]: line for line in map(json.loads, content.decode().splitlines())}


def _text(line: dict[str, Any], endpoint: str = "/v1/chat/completions") -> Any:
    body = line["response"]["body"]
    if endpoint == "/v1/chat/completions":
        return json.loads(body["choices"][0]["message"]["content"])
    message = next(item for item in body["output"] if item["type"] == "message")
    return json.loads(message["content"][0]["text"])


Start = Callable[..., AbstractContextManager[Any]]


@pytest.mark.parametrize("endpoint", ["/v1/chat/completions", "/v1/responses"])
def test_round_trip_through_the_states(batch_server: Start, requests: Any, endpoint: str) -> None:
    """20 requests with an image: validating, in progress (half answered), completed; the
    output file answers each custom_id with its reply; metadata, list and counts agree."""
    with batch_server(batch={"validating": 60, "in_progress": 600}) as server:
        batch = _submit(
            server, _lines(requests, endpoint), endpoint, {"bpb_run": "run1", "part": "0"}
        )
        assert batch.status == "validating" and batch.metadata == {"bpb_run": "run1", "part": "0"}
        server.advance(60 + 300)
        batch = litellm.retrieve_batch(batch_id=batch.id, **_kw(server))
        assert batch.status == "in_progress" and batch.output_file_id is None
        assert batch.request_counts.completed == N // 2
        server.advance(300)
        batch = litellm.retrieve_batch(batch_id=batch.id, **_kw(server))
        assert batch.status == "completed" and batch.error_file_id is None
        assert (batch.request_counts.total, batch.request_counts.completed) == (N, N)
        out = _file(server, batch.output_file_id)
        assert {cid: _text(line, endpoint) for cid, line in out.items()} == {
            f"run1-{i:03d}": requests.answer(i) for i in range(N)
        }
        assert all(line["response"]["status_code"] == 200 for line in out.values())
        listed = litellm.list_batches(limit=10, **_kw(server))
        assert [(b.id, b.metadata["bpb_run"]) for b in listed.data] == [(batch.id, "run1")]
        assert server.paid() == {f"run1-{i:03d}": 1 for i in range(N)}
        seen = server.server.stats()
        assert seen["images"] == N and seen["counts"] == {"unknown/unknown": N}


def test_failed_requests_go_to_the_error_file(batch_server: Start, requests: Any) -> None:
    """Per-request HTTP faults are error lines with their status and OpenAI's error body;
    only the answered ones are billed."""
    plan = ["ok", "500", "ok", "429", "400"] + ["ok"] * N
    with batch_server(faults={"unknown/unknown": plan}) as server:
        batch = _submit(server, _lines(requests))
        batch = litellm.retrieve_batch(batch_id=batch.id, **_kw(server))
        assert batch.status == "completed"
        assert (batch.request_counts.completed, batch.request_counts.failed) == (N - 3, 3)
        errors = _file(server, batch.error_file_id)
        assert {cid: line["response"]["status_code"] for cid, line in errors.items()} == {
            "run1-001": 500,
            "run1-003": 429,
            "run1-004": 400,
        }
        assert errors["run1-003"]["response"]["body"]["error"]["code"] == "rate_limit_exceeded"
        assert len(_file(server, batch.output_file_id)) == N - 3
        assert sorted(server.paid()) == sorted(
            f"run1-{i:03d}" for i in range(N) if i not in (1, 3, 4)
        )


def test_expired_batch_keeps_its_answers_and_names_the_rest(
    batch_server: Start, requests: Any
) -> None:
    """A provider that falls behind: 12 of 20 answered when the 24 h window ends; the rest are
    ``batch_expired`` error lines; a second batch of just those completes the work, and no
    custom_id is billed twice."""
    with batch_server(batch={"plan": [{"stall_after": 12}]}) as server:
        first = _submit(server, _lines(requests))
        server.advance(3600)
        assert litellm.retrieve_batch(batch_id=first.id, **_kw(server)).status == "in_progress"
        server.advance(86400)
        first = litellm.retrieve_batch(batch_id=first.id, **_kw(server))
        assert first.status == "expired" and first.expired_at is not None
        assert len(_file(server, first.output_file_id)) == 12
        left = _file(server, first.error_file_id)
        assert {line["error"]["code"] for line in left.values()} == {"batch_expired"}
        assert all(line["response"] is None for line in left.values())
        again = [line for line in _lines(requests) if line["custom_id"] in left]
        second = litellm.retrieve_batch(batch_id=_submit(server, again).id, **_kw(server))
        assert second.status == "completed"
        assert sorted(_file(server, second.output_file_id)) == sorted(left)
        assert server.paid() == {f"run1-{i:03d}": 1 for i in range(N)}


def test_hung_request_makes_the_batch_expire(batch_server: Start, requests: Any) -> None:
    """A request the provider never gets to (``hang``) holds its batch in progress until the
    window ends; then it alone is unanswered."""
    with batch_server(faults={"unknown/unknown": ["ok", "ok", "hang"]}) as server:
        batch = _submit(server, _lines(requests))
        assert litellm.retrieve_batch(batch_id=batch.id, **_kw(server)).status == "in_progress"
        server.advance(86400)
        batch = litellm.retrieve_batch(batch_id=batch.id, **_kw(server))
        assert batch.status == "expired"
        assert list(_file(server, batch.error_file_id)) == ["run1-002"]


def test_cancelled_batch(batch_server: Start, requests: Any) -> None:
    """Cancelled a quarter of the way: cancelling, then cancelled with the answers so far in
    the output file and the rest ``batch_cancelled``; an ended batch cannot be cancelled."""
    with batch_server(batch={"in_progress": 400, "cancelling": 30}) as server:
        batch = _submit(server, _lines(requests))
        server.advance(100)
        batch = litellm.cancel_batch(batch_id=batch.id, **_kw(server))
        assert batch.status == "cancelling"
        server.advance(30)
        batch = litellm.retrieve_batch(batch_id=batch.id, **_kw(server))
        assert batch.status == "cancelled" and batch.cancelled_at is not None
        assert len(_file(server, batch.output_file_id)) == N // 4
        left = _file(server, batch.error_file_id)
        assert len(left) == N - N // 4
        assert {line["error"]["code"] for line in left.values()} == {"batch_cancelled"}
        assert len(server.paid()) == N // 4
        with pytest.raises(Exception, match="Cannot cancel"):
            litellm.cancel_batch(batch_id=batch.id, **_kw(server))


def _failed(server: Any, lines: list[dict[str, Any]] | bytes) -> list[dict[str, Any]]:
    """Submit an input file and return the failed batch's errors."""
    content = lines if isinstance(lines, bytes) else _jsonl(lines)
    file = litellm.create_file(file=("in.jsonl", content), purpose="batch", **_kw(server))
    batch = litellm.create_batch(
        completion_window="24h",
        endpoint="/v1/chat/completions",
        input_file_id=file.id,
        **_kw(server),
    )
    batch = litellm.retrieve_batch(batch_id=batch.id, **_kw(server))
    assert batch.status == "failed" and batch.request_counts.total == 0
    assert batch.output_file_id is None
    return [e.model_dump() for e in batch.errors.data]


def test_inputs_the_api_refuses(batch_server: Start, requests: Any) -> None:
    """Bad lines fail the batch when it validates, each named with its line; bad uploads and
    batch parameters are refused at once; nothing is answered or billed."""
    lines = _lines(requests, n=4)
    with batch_server(batch={"openai_file_bytes": 40_000}) as server:
        dup = [lines[0], lines[1], {**lines[2], "custom_id": lines[0]["custom_id"]}]
        assert [(e["code"], e["line"]) for e in _failed(server, dup)] == [
            ("duplicate_custom_id", 3)
        ]
        other = {**lines[1], "body": requests.chat(1, model="gpt-4.1")}
        assert [e["code"] for e in _failed(server, [lines[0], other])] == ["mismatched_model"]
        broken = _jsonl(lines[:1]) + b'{"custom_id": "x", "method": "POST"\n'
        assert [(e["code"], e["line"]) for e in _failed(server, broken)] == [
            ("invalid_json_line", 2)
        ]
        missing = {k: v for k, v in lines[1].items() if k != "body"}
        assert [e["code"] for e in _failed(server, [lines[0], missing])] == [
            "missing_required_parameter"
        ]
        wrong_url = {**lines[1], "url": "/v1/responses"}
        assert [e["code"] for e in _failed(server, [lines[0], wrong_url])] == [
            "mismatched_endpoint"
        ]
        with pytest.raises(Exception, match="too large"):
            litellm.create_file(
                file=("big.jsonl", _jsonl(_lines(requests, n=200))), purpose="batch", **_kw(server)
            )
        file = litellm.create_file(
            file=("a.jsonl", _jsonl(lines)), purpose="user_data", **_kw(server)
        )
        with pytest.raises(Exception, match="purpose 'batch'"):
            litellm.create_batch(
                completion_window="24h",
                endpoint="/v1/chat/completions",
                input_file_id=file.id,
                **_kw(server),
            )
        with pytest.raises(Exception, match="metadata"):
            _submit(server, lines, metadata={f"k{i}": "v" for i in range(17)})
        assert server.paid() == {} and server.stats()["processed"] == {}


def test_batch_limits(batch_server: Start, requests: Any) -> None:
    """More requests or bytes than a batch may hold fail it (limits lowered for the test)."""
    with batch_server(batch={"openai_requests": 5, "openai_batch_bytes": 10_000_000}) as server:
        assert [e["code"] for e in _failed(server, _lines(requests, n=6))] == ["too_many_requests"]
    with batch_server(batch={"openai_batch_bytes": 1_000}) as server:
        assert [e["code"] for e in _failed(server, _lines(requests, n=6))] == ["file_too_large"]
