"""Each provider protocol of the paper's models, end to end against a local server speaking it.

litellm sends real HTTP to the fake server's Anthropic Messages, Gemini generateContent, OpenAI
Responses and OpenAI Chat endpoints. The tests check what each endpoint received (the image block
in the provider's own format, temperature sent or reported dropped, model arguments on the wire)
and what bpb recorded (tokens, cost against litellm's bundled price map, reasoning text), and
that 429/503/529 with Retry-After and 500 are retried on every protocol.
"""

from __future__ import annotations

import json
import urllib.request
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from bpb_testing.protocols import THOUGHT

from bpb_adapters.litellm_adapter.adapter import _import_litellm
from bpb_core.model_calls import AdapterOptions
from bpb_core.registry import Registry
from bpb_core.run_folder import iter_answers, read_attempts, read_manifest
from bpb_core.runner import run_eval
from bpb_core.runner.options import RetryPolicy, RunOptions
from support.fake_openai import FakeServer, fake_server

SCENES = ("h1_0000", "h1_0001", "h1_0002", "h3_0001")  # where the faults go
FAST = RetryPolicy(max_retries=3, base_delay=0.02, max_delay=1.0)
KEYS = {
    "OPENAI_API_KEY": "sk-bpbtest-0123456789abcdefSECRET",
    "ANTHROPIC_API_KEY": "sk-ant-bpbtest-0123456789abcdef",
    "GEMINI_API_KEY": "AIzaBPBTEST0123456789abcdef",
    "MOONSHOT_API_KEY": "sk-moon-bpbtest-0123456789abcdef",
}


@dataclass(frozen=True)
class Case:
    alias: str
    protocol: str
    path: str  # what --api-base adds to the server's root
    image: str
    args: dict[str, Any]
    on_wire: dict[str, Any]  # a parameter the model arguments must have become
    temperature_dropped: bool
    faults: tuple[str, ...]
    reasoning: bool = True  # the reply carries reasoning text and 20 reasoning tokens


CASES = [
    Case("gpt-5.4-pro", "openai-responses", "/v1", "openai-responses",
         {"reasoning_effort": "high"}, {"reasoning": {"effort": "high", "summary": "detailed"}},
         True,
         ("429", "503", "500")),
    Case("claude-opus-4.7", "anthropic", "", "anthropic-base64",
         {"max_tokens": 4000}, {"max_tokens": 4000}, True, ("429", "529", "503", "500"), False),
    Case("gemini-3-flash-preview", "gemini", "/v1beta", "gemini-inline",
         {"reasoning_effort": "low"}, {"generationConfig": {"temperature": 0.0, "thinkingConfig": {
             "thinkingLevel": "low", "includeThoughts": True}}}, False, ("429", "503", "500")),
    Case("kimi-k2.5", "openai-chat", "/v1", "openai-chat",
         {"top_p": 0.5}, {"top_p": 0.5}, True, ("429", "503", "500"), False),
]  # fmt: skip


def _requests(server: FakeServer) -> list[dict[str, Any]]:
    with urllib.request.urlopen(server.url + "/requests", timeout=10) as response:
        data: list[dict[str, Any]] = json.loads(response.read())
    return data


def _expected_cost(model: str) -> float:
    table = _import_litellm().model_cost
    entry = table.get(model) or table[model.split("/", 1)[1]]
    inp, out = entry["input_cost_per_token"], entry["output_cost_per_token"]
    cached = entry.get("cache_read_input_token_cost", inp)
    return 900 * inp + 100 * cached + 50 * out  # the server: 1000 in (100 cached), 50 out


@pytest.mark.parametrize("case", CASES, ids=[c.protocol for c in CASES])
def test_protocol_end_to_end(
    case: Case,
    dataset: Path,
    tmp_path: Path,
    registry: Registry,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    for name, value in KEYS.items():
        monkeypatch.setenv(name, value)
    faults = {f"{SCENES[i]}/q1": [fault] for i, fault in enumerate(case.faults)}
    config = {"faults": faults, "retry_after": 0.25}
    with fake_server(dataset, config, tmp_path) as server:
        options = AdapterOptions(api_base=server.url + case.path, model_args=case.args)
        adapter = registry.adapter(f"litellm:{case.alias}", options)
        assert adapter.preflight() is None  # type: ignore[attr-defined]
        run = tmp_path / "run"
        opts = RunOptions(timeout=10, retry=FAST, concurrency=4)
        result = run_eval(dataset, adapter, run, opts, registry=registry)
        seen = _requests(server)
    answers = [record for _, record in iter_answers(run)]
    assert len(answers) == 18 and all(a.status == "ok" for a in answers)
    assert result.api_errors == 0
    assert {r["protocol"] for r in seen} == {case.protocol}
    assert all(r["images"] == [{"format": case.image, "media": "image/png"}] for r in seen)
    for key, value in case.on_wire.items():
        assert all(r["params"].get(key) == value for r in seen), seen[0]["params"]
    sent = [json.dumps(r["params"]) for r in seen]
    assert all(('"temperature"' in s) != case.temperature_dropped for s in sent), sent[0]
    manifest = read_manifest(run) or {}
    assert ("temperature" in manifest["dropped_params"]) == case.temperature_dropped
    assert manifest["adapter_settings"]["model_args"] == case.args
    record = next(a for a in answers if a.scene_id == "h3_0000")
    assert record.usage.input_tokens == 1000 and record.usage.output_tokens == 50
    assert record.usage.cached_tokens == 100
    assert record.cost == pytest.approx(_expected_cost(adapter.model))  # type: ignore[attr-defined]
    attempts = list(read_attempts(run))
    ok = [e for e in attempts if e["outcome"] == "ok"]
    assert all(e["reasoning"] == (THOUGHT if case.reasoning else None) for e in ok)
    if case.reasoning:  # OpenAI reasoning_tokens, Gemini thoughtsTokenCount, as reported
        assert record.usage.reasoning_tokens == 20
    assert all(("temperature" in e["dropped"]) == case.temperature_dropped for e in ok)
    failed = {e["scene_id"]: e for e in attempts if e["outcome"] == "api_error"}
    for index, fault in enumerate(case.faults):
        entry = failed[SCENES[index]]
        assert entry["retry_in"] is not None, (fault, entry["error"])
        if fault != "500":  # the server's Retry-After is honoured
            assert entry["retry_in"] == pytest.approx(0.25), (fault, entry["error"])


def test_anthropic_thinking_budget_named_when_the_model_takes_an_effort_instead(
    dataset: Path, tmp_path: Path, registry: Registry, monkeypatch: pytest.MonkeyPatch
) -> None:
    """claude-opus-4.7 takes adaptive thinking only: bpb sends a budget as the effort litellm
    would have made of it silently, names the translation and records the reasoning."""
    monkeypatch.setenv("ANTHROPIC_API_KEY", KEYS["ANTHROPIC_API_KEY"])
    thinking = {"type": "enabled", "budget_tokens": 2000}
    with fake_server(dataset) as server:
        options = AdapterOptions(api_base=server.url, model_args={"thinking": thinking})
        adapter = registry.adapter("litellm:claude-opus-4.7", options)
        name = "litellm:claude-opus-4.7 [thinking=2000 as effort=low,temp=default]"
        assert adapter.name == name  # type: ignore[attr-defined]
        opts = RunOptions(timeout=10, retry=FAST, tasks=("q1",), limit=1, horizons=(1.0,))
        run_eval(dataset, adapter, tmp_path / "run", opts, registry=registry)
        seen = _requests(server)
    assert seen[0]["params"]["output_config"] == {"effort": "low"}
    entry = next(read_attempts(tmp_path / "run"))
    assert entry["outcome"] == "ok" and entry["dropped"] == [] and entry["reasoning"] == THOUGHT
    assert entry["usage"]["reasoning_tokens"] > 0
