"""The litellm adapter: aliases, prices from the offline map, overrides, lazy import."""

from __future__ import annotations

import asyncio
import subprocess
import sys
from pathlib import Path

import pytest

from bpb_adapters.litellm_adapter.aliases import resolve
from bpb_adapters.litellm_adapter.errors import redact
from bpb_core.errors import BadInput
from bpb_core.interfaces import PromptOptions
from bpb_core.model_calls import AdapterOptions, ModelRequest
from bpb_core.registry import make_registry
from support.fake_openai import fake_server
from support.runner_scenes import make_scene, png_bytes

REGISTRY = make_registry()


def _request(task: str = "q1") -> ModelRequest:
    scene = make_scene(1.0, 0)
    messages = REGISTRY.task(task).messages(scene, png_bytes(3), PromptOptions())
    return ModelRequest(messages, task, scene, timeout=10)


def test_aliases_reach_provider_ids_and_user_aliases_win() -> None:
    assert resolve("claude-opus-4.7") == "anthropic/claude-opus-4-7"
    assert resolve("openai/some-new-model") == "openai/some-new-model"
    assert resolve("claude-opus-4.7", {"claude-opus-4.7": "bedrock/x"}) == "bedrock/x"


def test_known_model_is_priced_offline_and_override_wins(tmp_path: Path, secret_key: str) -> None:
    with fake_server(None) as server:
        base = AdapterOptions(api_base=server.api_base)
        priced = REGISTRY.adapter("litellm:gpt-4o", base)
        reply = asyncio.run(priced.complete(_request()))
        assert priced.model == "openai/gpt-4o"
        assert reply.cost is not None and reply.cost > 0
        assert reply.usage.input_tokens == 1000 and reply.usage.reasoning_tokens == 20
        custom = AdapterOptions(api_base=server.api_base,
                                prices={"gpt-4o": {"input": 1e-6, "output": 2e-6}})  # fmt: skip
        override = asyncio.run(REGISTRY.adapter("litellm:gpt-4o", custom).complete(_request()))
        assert override.cost == pytest.approx(1000 * 1e-6 + 50 * 2e-6)
        cached = {"gpt-4o": {"input": 1e-6, "output": 2e-6, "cache_read": 1e-7}}
        cheap = REGISTRY.adapter("litellm:gpt-4o", AdapterOptions(server.api_base, prices=cached))
        reply = asyncio.run(cheap.complete(_request()))  # 100 of the 1000 input tokens cached
        assert reply.cost == pytest.approx(900 * 1e-6 + 100 * 1e-7 + 50 * 2e-6)
        unknown = REGISTRY.adapter("litellm:openai/no-such-model-xyz", base)
        assert asyncio.run(unknown.complete(_request("q3"))).cost is None
        assert server.stats()["images"] == 4


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -1e-6])
def test_a_library_price_override_must_be_an_amount(value: float) -> None:
    # the library path (no --prices file checked by the command line): a NaN price would make
    # every cost NaN, which no --max-cost ever reaches
    options = AdapterOptions(prices={"gpt-4o": {"input": 1e-6, "output": value}})
    with pytest.raises(BadInput, match=r"price of gpt-4o: price 'output' must be a finite number"):
        REGISTRY.adapter("litellm:gpt-4o", options)


def test_a_library_model_argument_must_be_json() -> None:
    # JSON has no NaN: every call would fail as an api_error, after its retries
    options = AdapterOptions(model_args={"thinking": {"budget_tokens": float("nan")}})
    with pytest.raises(BadInput, match=r"model argument thinking.budget_tokens: must be a finite"):
        REGISTRY.adapter("litellm:gpt-4o", options)


def test_secrets_are_redacted(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ANTHROPIC_API_KEY", "abc-secret-value-42")
    text = redact("failed with abc-secret-value-42 and sk-proj-ABCDEFGHIJKLMNOPQRSTUV")
    assert "abc-secret-value-42" not in text and "ABCDEFGHIJKLMNOP" not in text


def test_litellm_and_pandas_are_imported_only_when_used() -> None:
    code = (
        "import sys, bpb_core, bpb_core.runner, bpb_adapters.litellm_adapter.hooks;"
        "from bpb_core.registry import make_registry; make_registry();"
        "print('litellm' in sys.modules, 'pandas' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]
