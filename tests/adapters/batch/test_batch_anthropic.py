"""Anthropic's Message Batches against the fake server over real HTTP on 127.0.0.1: through the
official ``anthropic`` SDK, and the part the pinned litellm covers.

litellm 1.106.2 reaches Anthropic batches only through ``retrieve_batch`` and ``file_content``
(the batch id as file id: the results JSON lines, unchanged); ``create_batch``,
``cancel_batch`` and ``list_batches`` refuse ``custom_llm_provider="anthropic"``. The SDK
covers all of it: create, retrieve, results, cancel, list.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from contextlib import AbstractContextManager
from typing import Any

import pytest

anthropic = pytest.importorskip("anthropic")
litellm = pytest.importorskip("litellm")

N = 20
Start = Callable[..., AbstractContextManager[Any]]


def _client(server: Any) -> Any:
    return anthropic.Anthropic(api_key="sk-ant-bpb-test", base_url=server.url, max_retries=0)


def _batch(client: Any, requests: Any, n: int = N) -> Any:
    items = [{"custom_id": f"run1-{i:03d}", "params": requests.anthropic(i)} for i in range(n)]
    return client.messages.batches.create(requests=items)


def _results(client: Any, batch_id: str) -> dict[str, Any]:
    return {r.custom_id: r.result for r in client.messages.batches.results(batch_id)}


def test_round_trip_with_the_sdk(batch_server: Start, requests: Any) -> None:
    """20 requests with an image: in progress (every request ``processing``), then ended with
    a ``succeeded`` result per custom_id; listed; billed once each."""
    with batch_server(batch={"in_progress": 600}) as server:
        client = _client(server)
        batch = _batch(client, requests)
        assert batch.processing_status == "in_progress" and batch.results_url is None
        server.advance(300)
        batch = client.messages.batches.retrieve(batch.id)
        assert batch.processing_status == "in_progress"
        assert batch.request_counts.processing == N
        server.advance(300)
        batch = client.messages.batches.retrieve(batch.id)
        assert batch.processing_status == "ended" and batch.request_counts.succeeded == N
        results = _results(client, batch.id)
        assert {cid: json.loads(r.message.content[0].text) for cid, r in results.items()} == {
            f"run1-{i:03d}": requests.answer(i) for i in range(N)
        }
        assert [b.id for b in client.messages.batches.list(limit=5)] == [batch.id]
        assert server.paid() == {f"run1-{i:03d}": 1 for i in range(N)}
        assert server.server.stats()["images"] == N


def test_litellm_retrieves_and_downloads_but_cannot_create(
    batch_server: Start, requests: Any
) -> None:
    """The pinned litellm's reach: ``retrieve_batch`` and ``file_content`` work; the rest
    refuse the provider."""
    with batch_server() as server:
        batch = _batch(_client(server), requests, n=3)
        kw = {"custom_llm_provider": "anthropic", "api_base": server.url, "api_key": "sk-ant-x"}
        got = litellm.retrieve_batch(batch_id=batch.id, **kw)
        assert got.id == batch.id and got.status == "completed"
        content = litellm.file_content(file_id=batch.id, **kw).content
        lines = [json.loads(line) for line in content.decode().splitlines()]
        assert [(x["custom_id"], x["result"]["type"]) for x in lines] == [
            (f"run1-{i:03d}", "succeeded") for i in range(3)
        ]
        for call in (
            lambda: litellm.create_batch(
                completion_window="24h",
                endpoint="/v1/chat/completions",
                input_file_id="file-x",
                **kw,
            ),
            lambda: litellm.cancel_batch(batch_id=batch.id, **kw),
            lambda: litellm.list_batches(**kw),
        ):
            with pytest.raises(Exception, match="support"):
                call()


def test_errored_expired_and_canceled_results(batch_server: Start, requests: Any) -> None:
    """Per-request faults end ``errored`` with Anthropic's error body; a batch that falls
    behind ends ``expired`` after 24 h for the rest; a cancelled one ``canceled``; invalid
    params end ``errored`` without being billed."""
    plan = ["ok", "529", "ok", "500"] + ["ok"] * 2 * N
    config = {"plan": [{}, {"stall_after": 5}, {}], "in_progress": 100, "cancelling": 10}
    with batch_server(faults={"unknown/unknown": plan}, batch=config) as server:
        client = _client(server)
        first = _batch(client, requests, n=6)
        server.advance(100)
        counts = client.messages.batches.retrieve(first.id).request_counts
        assert (counts.succeeded, counts.errored) == (4, 2)
        errored = _results(client, first.id)["run1-001"]
        assert errored.type == "errored" and errored.error.error.type == "overloaded_error"
        second = _batch(client, requests)
        third = _batch(client, requests)
        server.advance(40)
        assert client.messages.batches.cancel(third.id).processing_status == "canceling"
        server.advance(100)
        assert client.messages.batches.retrieve(second.id).processing_status == "in_progress"
        server.advance(86400)
        counts = client.messages.batches.retrieve(second.id).request_counts
        assert (counts.succeeded, counts.expired) == (5, N - 5)
        canceled = client.messages.batches.retrieve(third.id)
        assert canceled.processing_status == "ended" and canceled.cancel_initiated_at is not None
        kinds = [r.type for r in _results(client, third.id).values()]
        assert kinds.count("canceled") == N - kinds.count("succeeded") and "canceled" in kinds
        bad = requests.anthropic(0)
        del bad["max_tokens"]
        invalid = client.messages.batches.create(requests=[{"custom_id": "bad-1", "params": bad}])
        server.advance(100)
        assert _results(client, invalid.id)["bad-1"].error.error.type == "invalid_request_error"
        assert "bad-1" not in server.paid()
        assert sum(server.paid().values()) == 4 + 5 + kinds.count("succeeded")  # succeeded only


def test_requests_the_api_refuses(batch_server: Start, requests: Any) -> None:
    """A repeated or malformed custom_id, a request without params, no requests and a batch
    over the request limit are refused at once (400/413)."""
    with batch_server(batch={"anthropic_requests": 3}) as server:
        client = _client(server)
        params = requests.anthropic(0)
        cases = {
            "Duplicate custom_id": [{"custom_id": "a", "params": params}] * 2,
            "should match pattern": [{"custom_id": "a b", "params": params}],
            "params: Field required": [{"custom_id": "a"}],
            "at least 1 item": [],
        }
        for message, items in cases.items():
            with pytest.raises(anthropic.BadRequestError, match=message):
                client.messages.batches.create(requests=items)
        with pytest.raises(anthropic.APIStatusError, match="at most 3"):
            _batch(client, requests, n=4)
        assert server.stats()["jobs"] == {}
