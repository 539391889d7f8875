"""The provider accepts a batch and the reply never arrives (``drop_reply``: what a kill -9
between submission and recording leaves): the client finds the batch by listing, by the run's id
in its metadata (OpenAI), display name (Gemini) or creation time and size (Anthropic, which has
neither), and collects it; every request is billed once.

Also pinned here: the clients retry a create call whose connection dropped unless told not to
(the openai SDK under litellm, the anthropic SDK), which submits the batch twice; bpb must create
with retries off and adopt instead.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from contextlib import AbstractContextManager
from typing import Any

import pytest

litellm = pytest.importorskip("litellm")

N = 6
Start = Callable[..., AbstractContextManager[Any]]
DROP = {"plan": [{"drop_reply": True}]}


def _openai_submit(server: Any, requests: Any, retries: int | None) -> Any:
    kw = {"custom_llm_provider": "openai", "api_base": server.url + "/v1", "api_key": "sk-x"}
    lines = [
        {
            "custom_id": f"r1-0-{i}",
            "method": "POST",
            "url": "/v1/chat/completions",
            "body": requests.chat(i),
        }
        for i in range(N)
    ]
    content = "\n".join(json.dumps(line) for line in lines).encode()
    file = litellm.create_file(file=("b.jsonl", content), purpose="batch", **kw)
    return litellm.create_batch(
        completion_window="24h",
        endpoint="/v1/chat/completions",
        input_file_id=file.id,
        metadata={"bpb_run": "r1", "bpb_intent": "r1-0"},
        **({} if retries is None else {"max_retries": retries}),
        **kw,
    )


def test_openai_adopts_by_metadata(batch_server: Start, requests: Any) -> None:
    kw = {"custom_llm_provider": "openai", "api_base": "", "api_key": "sk-x"}
    with batch_server(batch=DROP) as server:
        kw["api_base"] = server.url + "/v1"
        with pytest.raises(Exception):  # noqa: B017 - whichever connection error litellm maps it to
            _openai_submit(server, requests, retries=0)
        found = [b for b in litellm.list_batches(**kw).data if b.metadata["bpb_intent"] == "r1-0"]
        assert len(found) == 1
        batch = litellm.retrieve_batch(batch_id=found[0].id, **kw)
        assert batch.status == "completed" and batch.request_counts.completed == N
        assert server.paid() == {f"r1-0-{i}": 1 for i in range(N)}


def test_openai_create_retried_by_default_submits_twice(batch_server: Start, requests: Any) -> None:
    with batch_server(batch=DROP) as server:
        batch = _openai_submit(server, requests, retries=None)  # litellm's default
        assert batch.status == "validating"
        assert len(server.stats()["jobs"]) == 2  # the dropped one runs too
        assert set(server.paid().values()) == {2}


def test_anthropic_adopts_by_time_and_size(batch_server: Start, requests: Any) -> None:
    anthropic = pytest.importorskip("anthropic")
    items = [{"custom_id": f"r1-0-{i}", "params": requests.anthropic(i)} for i in range(N)]
    with batch_server(batch={"plan": [{"drop_reply": True}, {"drop_reply": True}]}) as server:
        client = anthropic.Anthropic(api_key="k", base_url=server.url, max_retries=0)
        intent_time = time.time() - 1
        with pytest.raises(anthropic.APIConnectionError):
            client.messages.batches.create(requests=items)
        candidates = [
            b
            for b in client.messages.batches.list()
            if b.created_at.timestamp() >= intent_time
            and sum(b.request_counts.to_dict().values()) == N
        ]
        assert len(candidates) == 1
        results = {r.custom_id for r in client.messages.batches.results(candidates[0].id)}
        assert results == {item["custom_id"] for item in items}  # the custom ids confirm it
        assert server.paid() == {f"r1-0-{i}": 1 for i in range(N)}
        retried = anthropic.Anthropic(api_key="k", base_url=server.url, max_retries=2)
        retried.messages.batches.create(requests=items)  # the second drop, then a retry
        assert len(server.stats()["jobs"]) == 3


def test_gemini_adopts_by_display_name(batch_server: Start, requests: Any) -> None:
    genai = pytest.importorskip("google.genai")
    from google.genai import types

    src = [
        {
            "contents": [{"role": "user", "parts": [{"text": requests.prompt(i)}]}],
            "metadata": {"key": f"r1-0-{i}"},
        }
        for i in range(N)
    ]
    with batch_server(batch=DROP) as server:
        options = types.HttpOptions(
            base_url=server.url, retry_options=types.HttpRetryOptions(attempts=1)
        )
        client = genai.Client(api_key="AIza-x", http_options=options)
        with pytest.raises(Exception):  # noqa: B017 - httpx's RemoteProtocolError, unwrapped
            client.batches.create(
                model="gemini-3-flash-preview", src=src, config={"display_name": "bpb-r1-0"}
            )
        [job] = [j for j in client.batches.list() if j.display_name == "bpb-r1-0"]
        job = client.batches.get(name=job.name)
        assert job.state == "JOB_STATE_SUCCEEDED" and len(job.dest.inlined_responses) == N
        assert server.paid() == {f"r1-0-{i}": 1 for i in range(N)}
