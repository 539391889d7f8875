"""A batch line can carry exactly the body a synchronous call sends: the pinned litellm renders
it without sending anything (``litellm.utils.return_raw_request``, public but marked beta), and
that body is the one ``litellm.completion`` puts on the wire, for each of the paper's protocols
(OpenAI chat, OpenAI Responses for the Pro models, Anthropic Messages, Gemini generateContent).

Checked against the fake server, which keeps whole request bodies with ``keep_bodies``; then the
rendered body goes through the provider's batch endpoint and is answered like the synchronous
call.
"""

from __future__ import annotations

import json
import urllib.request
from collections.abc import Callable
from contextlib import AbstractContextManager
from typing import Any

import pytest

litellm = pytest.importorskip("litellm")

Start = Callable[..., AbstractContextManager[Any]]
CASES = [  # model, what --api-base adds to the server's root, extra model arguments
    ("openai/gpt-4.1-mini", "/v1", {}),
    ("openai/gpt-5.4-pro", "/v1", {"reasoning_effort": "high"}),
    ("anthropic/claude-opus-4-7", "", {"max_tokens": 4000}),
    ("gemini/gemini-3-flash-preview", "/v1beta", {"reasoning_effort": "low"}),
]


def _kwargs(requests: Any, model: str, api_base: str, extra: dict[str, Any]) -> dict[str, Any]:
    """The arguments bpb's litellm adapter passes (adapter.complete)."""
    url = "data:image/png;base64," + requests.b64
    content = [
        {"type": "text", "text": requests.prompt(7)},
        {"type": "image_url", "image_url": {"url": url}},
    ]
    return {
        "model": model,
        "messages": [{"role": "user", "content": content}],
        "temperature": 0,
        "max_tokens": 300,
        **extra,
        "timeout": 30,
        "max_retries": 0,
        "drop_params": True,
        "api_base": api_base,
        "api_key": "sk-bpb-test",
    }


def _rendered(kwargs: dict[str, Any]) -> dict[str, Any]:
    from litellm.types.utils import CallTypes
    from litellm.utils import return_raw_request

    kwargs = {k: v for k, v in kwargs.items() if k != "api_key"}  # it sets a key of its own
    raw = return_raw_request(CallTypes.completion, kwargs)
    assert not raw.get("error"), raw
    body = dict(raw["raw_request_body"])
    body.update(body.pop("extra_body", None) or {})  # the openai SDK merges it into the JSON
    return body


def _last_body(server: Any) -> dict[str, Any]:
    with urllib.request.urlopen(server.url + "/requests", timeout=10) as response:
        seen: list[dict[str, Any]] = json.loads(response.read())
    return seen[-1]["body"]


@pytest.mark.parametrize(("model", "path", "extra"), CASES, ids=[c[0] for c in CASES])
def test_rendered_body_is_the_wire_body(
    batch_server: Start, requests: Any, model: str, path: str, extra: dict[str, Any]
) -> None:
    with batch_server(keep_bodies=True) as server:
        kwargs = _kwargs(requests, model, server.url + path, extra)
        rendered = _rendered(kwargs)
        reply = litellm.completion(**kwargs)
        assert json.loads(reply.choices[0].message.content) == requests.answer(7)
        sent = _last_body(server)
        assert rendered == sent
        # the rendered body through the provider's batch endpoint gets the same answer
        provider = model.split("/")[0]
        if provider == "openai":
            endpoint = "/v1/responses" if "input" in sent else "/v1/chat/completions"
            line = {"custom_id": "p7", "method": "POST", "url": endpoint, "body": rendered}
            kw = {"custom_llm_provider": "openai", "api_base": server.url + "/v1", "api_key": "k"}
            file = litellm.create_file(
                file=("b.jsonl", json.dumps(line).encode()), purpose="batch", **kw
            )
            batch = litellm.create_batch(
                completion_window="24h", endpoint=endpoint, input_file_id=file.id, **kw
            )
            batch = litellm.retrieve_batch(batch_id=batch.id, **kw)
            out = json.loads(litellm.file_content(file_id=batch.output_file_id, **kw).content)
            assert out["response"]["status_code"] == 200
        elif provider == "anthropic":
            anthropic = pytest.importorskip("anthropic")
            client = anthropic.Anthropic(api_key="k", base_url=server.url)
            batch = client.messages.batches.create(
                requests=[{"custom_id": "p7", "params": rendered}]
            )
            [result] = list(client.messages.batches.results(batch.id))
            assert json.loads(result.result.message.content[0].text) == requests.answer(7)
        else:
            body = json.dumps(
                {
                    "batch": {
                        "displayName": "p",
                        "inputConfig": {
                            "requests": {
                                "requests": [{"request": rendered, "metadata": {"key": "p7"}}]
                            }
                        },
                    }
                }
            ).encode()
            url = f"{server.url}/v1beta/models/gemini-3-flash-preview:batchGenerateContent"
            post = urllib.request.Request(url, body, {"Content-Type": "application/json"})
            with urllib.request.urlopen(post, timeout=10) as response:
                name = json.loads(response.read())["name"]
            with urllib.request.urlopen(f"{server.url}/v1beta/{name}", timeout=10) as response:
                op = json.loads(response.read())
            [item] = op["metadata"]["output"]["inlinedResponses"]["inlinedResponses"]
            parts = item["response"]["candidates"][0]["content"]["parts"]
            assert json.loads(parts[-1]["text"]) == requests.answer(7)
        assert server.paid() == {"p7": 1}
