"""--structured-output offers each task's answer schema on the wire; off by default."""

from __future__ import annotations

import json
import urllib.request
from pathlib import Path
from typing import Any

import pytest

from bpb_core import RunOptions, answer_schema, run_eval
from bpb_core.model_calls import AdapterOptions
from bpb_core.registry import Registry
from bpb_core.run_folder import iter_answers
from bpb_core.runner.options import RetryPolicy
from support.fake_openai import FakeServer, fake_server

FAST = RetryPolicy(max_retries=2, base_delay=0.02, max_delay=1.0)


def _params(server: FakeServer) -> list[dict[str, Any]]:
    with urllib.request.urlopen(server.url + "/requests", timeout=10) as response:
        seen: list[dict[str, Any]] = json.loads(response.read())
    return [r["params"] for r in seen]


def _run(dataset: Path, out: Path, registry: Registry, spec: str, base: str, on: bool) -> Any:
    adapter = registry.adapter(spec, AdapterOptions(api_base=base or None))
    options = RunOptions(limit=1, timeout=10, retry=FAST, structured_output=on)
    return run_eval(dataset, adapter, out, options, registry=registry)


def test_openai_route_sends_the_published_schema_only_when_asked(
    dataset: Path, tmp_path: Path, registry: Registry, secret_key: str
) -> None:
    with fake_server(dataset) as server:
        base = server.url + "/v1"
        _run(dataset, tmp_path / "off", registry, "litellm:openai/fake", base, False)
        assert all("response_format" not in p for p in _params(server))
        result = _run(dataset, tmp_path / "on", registry, "litellm:openai/fake", base, True)
        sent = [p["response_format"] for p in _params(server) if "response_format" in p]
    assert result.api_errors == 0
    assert all(r.status == "ok" for _, r in iter_answers(tmp_path / "on"))
    assert len(sent) == 6  # 2 scenes x 3 tasks
    for fmt in sent:
        task = fmt["json_schema"]["name"].removesuffix("_answer")
        assert fmt["type"] == "json_schema"
        assert fmt["json_schema"]["schema"] == answer_schema(task)
    manifest = json.loads((tmp_path / "on" / "run.json").read_text())
    assert manifest["options"]["structured_output"] is True
    assert secret_key not in (tmp_path / "on" / "run.json").read_text()


def test_resume_with_the_other_setting_is_refused(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    from bpb_core.errors import BadInput

    _run(dataset, tmp_path / "r", registry, "baseline:oracle", "", True)
    with pytest.raises(BadInput, match="structured_output"):
        _run(dataset, tmp_path / "r", registry, "baseline:oracle", "", False)
