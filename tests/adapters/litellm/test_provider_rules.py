"""Provider rules, against the local Anthropic Messages server that rejects what the API does.

Anthropic's extended thinking takes no temperature but 1: before, the documented Opus 4.5/4.6
thinking setting sent ``temperature: 0`` with ``thinking`` and every call was a 400. On Opus 4.7
(adaptive thinking only) a thinking budget became an effort inside litellm while the run was
labelled ``thinking=8000``; now bpb makes the translation and names it.
"""

from __future__ import annotations

import json
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

import pytest

from bpb_adapters.litellm_adapter.rules import TEMPERATURE_NOTE, plan
from bpb_core.errors import BadInput
from bpb_core.model_calls import AdapterOptions
from bpb_core.registry import Registry
from bpb_core.run_folder import iter_answers, read_manifest
from bpb_core.runner import run_eval
from bpb_core.runner.options import RetryPolicy, RunOptions
from support.fake_openai import FakeServer, fake_server

THINKING = {"thinking": {"type": "enabled", "budget_tokens": 8000}, "max_tokens": 16000}


def _requests(server: FakeServer) -> list[dict[str, Any]]:
    with urllib.request.urlopen(server.url + "/requests", timeout=10) as response:
        data: list[dict[str, Any]] = json.loads(response.read())
    return data


def _run(registry: Registry, server: FakeServer, alias: str, run: Path, data: Path) -> str:
    options = AdapterOptions(api_base=server.url, model_args=THINKING)
    adapter = registry.adapter(f"litellm:{alias}", options)
    opts = RunOptions(timeout=10, retry=RetryPolicy(max_retries=0), tasks=("q1",), limit=1)
    run_eval(data, adapter, run, opts, registry=registry)
    return str(adapter.name)  # type: ignore[attr-defined]


def test_the_server_rejects_temperature_with_thinking_as_anthropic_documents(
    dataset: Path, tmp_path: Path
) -> None:
    body = {
        "model": "claude-opus-4-5",
        "max_tokens": 16000,
        "temperature": 0,
        "thinking": THINKING["thinking"],
        "messages": [{"role": "user", "content": "x"}],
    }
    with fake_server(dataset) as server:
        request = urllib.request.Request(
            server.url + "/v1/messages",
            json.dumps(body).encode(),
            {"Content-Type": "application/json"},
        )
        with pytest.raises(urllib.error.HTTPError) as caught:
            urllib.request.urlopen(request, timeout=10)
    assert caught.value.code == 400
    error = json.loads(caught.value.read())["error"]
    assert error["type"] == "invalid_request_error" and "temperature" in error["message"]


@pytest.mark.parametrize("alias", ["claude-opus-4.5", "claude-opus-4.6"])
def test_thinking_sends_no_temperature_and_the_run_records_the_provider_default(
    alias: str, dataset: Path, tmp_path: Path, registry: Registry, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("ANTHROPIC_API_KEY", "sk-ant-bpbtest-0123456789abcdef")
    with fake_server(dataset) as server:
        name = _run(registry, server, alias, tmp_path / "run", dataset)
        seen = _requests(server)
    assert all(r["params"]["thinking"] == THINKING["thinking"] for r in seen)
    assert all("temperature" not in r["params"] for r in seen)
    assert {a.status for _, a in iter_answers(tmp_path / "run")} == {"ok"}
    manifest = read_manifest(tmp_path / "run") or {}
    assert manifest["adapter_settings"]["rules"] == [TEMPERATURE_NOTE]
    assert name == f"litellm:{alias} [max_tokens=16000,thinking=8000,temp=default]"


def test_on_opus_4_7_a_thinking_budget_is_sent_as_a_named_effort(
    dataset: Path, tmp_path: Path, registry: Registry, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("ANTHROPIC_API_KEY", "sk-ant-bpbtest-0123456789abcdef")
    with fake_server(dataset) as server:
        name = _run(registry, server, "claude-opus-4.7", tmp_path / "run", dataset)
        seen = _requests(server)
    assert all(r["params"]["output_config"] == {"effort": "high"} for r in seen)
    assert all(r["params"]["thinking"]["type"] == "adaptive" for r in seen)
    assert {a.status for _, a in iter_answers(tmp_path / "run")} == {"ok"}
    manifest = read_manifest(tmp_path / "run") or {}
    assert manifest["adapter_settings"]["rules"][0].startswith(
        "thinking.budget_tokens: 8000 sent as reasoning_effort 'high'"
    )
    assert manifest["adapter_settings"]["model_args"] == THINKING  # what the user asked
    assert manifest["dropped_params"] == []  # nothing left for litellm to drop silently
    assert "thinking=8000 as effort=high" in name


@pytest.mark.parametrize(
    ("budget", "effort"), [(1024, "low"), (2048, "medium"), (4096, "high"), (8000, "high"),
                           (8192, "xhigh")],
)  # fmt: skip
def test_budget_to_effort_follows_litellm_thresholds(budget: int, effort: str) -> None:
    entry = {"supports_adaptive_thinking": True, "supports_xhigh_reasoning_effort": True}
    args = {"thinking": {"type": "enabled", "budget_tokens": budget}}
    assert plan("anthropic/claude-opus-4-7", args, entry).args == {"reasoning_effort": effort}


@pytest.mark.parametrize(
    ("args", "named"),
    [({"temperature": 0}, "temperature"), ({"top_k": 5}, "top_k"), ({"top_p": 0.5}, "top_p")],
)
def test_an_argument_thinking_rejects_is_refused_before_any_call(
    args: dict[str, Any], named: str, registry: Registry
) -> None:
    options = AdapterOptions(model_args={**THINKING, **args})
    with pytest.raises(BadInput, match=rf"model argument {named}: Anthropic's extended thinking"):
        registry.adapter("litellm:claude-opus-4.5", options)


def test_other_providers_and_thinking_off_keep_the_run_s_temperature() -> None:
    assert plan("openai/gpt-5.4", {"reasoning_effort": "high"}, {}).temperature
    assert plan("anthropic/claude-opus-4-5", {"max_tokens": 100}, {}).temperature
    assert not plan("anthropic/claude-opus-4-5", {"reasoning_effort": "low"}, {}).temperature
