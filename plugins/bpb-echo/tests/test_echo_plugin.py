"""The example plugin, found through its installed entry point."""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
from pathlib import Path

import pytest

from bpb_core import Message, ModelRequest, TextPart, make_registry
from bpb_core.errors import BadInput

BPB = str(Path(sys.executable).with_name("bpb"))


def test_bpb_plugins_lists_the_installed_example() -> None:
    result = subprocess.run([BPB, "plugins", "--json"], capture_output=True, text=True, check=True)
    rows = {r["name"]: r for r in json.loads(result.stdout)}
    assert rows["echo"]["distribution"] == "bpb-echo"
    assert rows["echo"]["version"] == "0.1.0"
    assert rows["echo"]["models"] == ["prompt", "upper"]


def test_echo_replies_with_the_prompt_text() -> None:
    adapter = make_registry().adapter("echo:prompt")
    prompt = 'Answer as JSON, e.g. {"answers": []}'
    request = ModelRequest(messages=(Message("user", (TextPart(prompt),)),), task="q1")
    reply = asyncio.run(adapter.complete(request))
    assert reply.text == prompt
    assert reply.cost is None and reply.finish_reason == "stop"


def test_upper_never_contains_json() -> None:
    adapter = make_registry().adapter("echo:upper")
    request = ModelRequest(messages=(Message("user", (TextPart('{"a": 1}'),)),), task="q1")
    reply = asyncio.run(adapter.complete(request))
    assert "{" not in reply.text and "A" in reply.text


def test_unknown_echo_model_is_bad_input() -> None:
    with pytest.raises(BadInput, match="echo:prompt"):
        make_registry().adapter("echo:nonsense")


def test_bpb_run_drives_the_plugin_end_to_end(tmp_path: Path) -> None:
    data, runs = tmp_path / "data", tmp_path / "runs"
    subprocess.run(
        [BPB, "generate", "--out", str(data), "--per-horizon", "1", "--horizons", "1"],
        check=True,
        capture_output=True,
    )
    result = subprocess.run(
        [BPB, "run", "--data", str(data), "--adapter", "echo:prompt", "--adapter", "echo:upper",
         "--tasks", "q1,q3", "--out", str(runs)],
        capture_output=True,
        text=True,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    parsed = json.loads((runs / "echo_prompt" / "h1" / "scene_0000" / "q1.json").read_text())
    shouted = json.loads((runs / "echo_upper" / "h1" / "scene_0000" / "q3.json").read_text())
    assert parsed["status"] == "ok" and parsed["answer"]["answers"]
    assert shouted["status"] == "parse_error" and shouted["attempts"] > 1
