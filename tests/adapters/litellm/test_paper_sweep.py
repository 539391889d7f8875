"""The paper's sweep from ``examples/paper.toml``: every model against the local protocol servers
(an ``api_base`` per adapter in the run file), through the real ``bpb`` command, then a report."""

from __future__ import annotations

import functools
import json
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bpb_adapters.litellm_adapter.aliases import PAPER_MODELS, resolve
from bpb_core.run_folder import iter_answers, read_attempts, read_manifest
from support.fake_openai import fake_server
from support.inprocess import Done, bpb
from support.paths import REPO

RunBpb = Callable[..., Done]
KEYS = ("OPENAI", "ANTHROPIC", "GEMINI", "DASHSCOPE", "MOONSHOT", "VOLCENGINE")
# What litellm 1.106.2 does with temperature 0 for these models (the finding).
DROPS_TEMPERATURE = ("gpt-5.2-pro", "gpt-5.4-pro", "gpt-5.5", "gpt-5.5-pro", "claude-opus-4.7",
                     "kimi-k2.5", "gpt-5.4 [effort=high]")  # fmt: skip
PATHS = {"anthropic": "", "gemini": "/v1beta"}  # every other provider: /v1


@pytest.fixture
def run_bpb(site: Path, capfd: pytest.CaptureFixture[str]) -> RunBpb:
    """``bpb ARGS`` in this process, ``site`` first on ``sys.path`` (conftest's ``run_bpb``
    runs the console script)."""
    return functools.partial(bpb, capfd, site=site)


def _toml(value: Any) -> str:
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {_toml(v)}" for k, v in value.items()) + "}"
    return json.dumps(value)


def _run_file(path: Path, url: str) -> list[str]:
    """The shipped run file with every adapter pointed at ``url``, plus a second option set."""
    data = tomllib.loads((REPO / "examples" / "paper.toml").read_text(encoding="utf-8"))
    adapters = [*data["adapter"], {"spec": "litellm:gpt-5.4", "args": {"reasoning_effort": "high"}}]
    lines = ["[defaults]", *(f"{k} = {_toml(v)}" for k, v in data["defaults"].items())]
    for table in adapters:
        provider = resolve(table["spec"].split(":", 1)[1]).split("/", 1)[0]
        table = {**table, "api_base": url + PATHS.get(provider, "/v1"), "timeout": 20}
        lines += ["", "[[adapter]]", *(f"{k} = {_toml(v)}" for k, v in table.items())]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return [t["spec"] for t in adapters]


@pytest.mark.slow
def test_paper_sweep_answers_every_pair_with_usage_and_one_report_row_per_option_set(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    for name in KEYS:
        monkeypatch.setenv(f"{name}_API_KEY", f"sk-{name.lower()}-bpbtest-0123456789abcdef")
    out = tmp_path / "runs"
    with fake_server(dataset) as server:
        specs = _run_file(tmp_path / "paper.toml", server.url)
        done = run_bpb("run", "--config", str(tmp_path / "paper.toml"), "--data", str(dataset),
                       "--out", str(out), "--limit", "1", "--horizons", "1")  # fmt: skip
        protocols = {r["protocol"] for r in json.loads(_get(server.url + "/requests"))}
    assert done.returncode == 0, done.stderr
    assert len(PAPER_MODELS) == 17 and len(specs) == 18
    assert protocols == {"openai-chat", "openai-responses", "anthropic", "gemini"}
    warned = [line for line in done.stderr.splitlines() if "temperature not sent" in line]
    assert len(warned) == len(DROPS_TEMPERATURE)  # once per adapter, not once per call
    assert all(any(f"litellm:{m}:" in w for w in warned) for m in DROPS_TEMPERATURE)
    folders = sorted(p for p in out.iterdir() if (p / "run.json").is_file())
    assert len(folders) == 18
    assert {"litellm_gpt-5.4", "litellm_gpt-5.4_effort=high"} <= {p.name for p in folders}
    for folder in folders:
        answers = [r for _, r in iter_answers(folder)]
        assert len(answers) == 3 and all(a.status == "ok" for a in answers), folder
        assert all(a.usage.input_tokens == 1000 and a.usage.output_tokens == 50 for a in answers)
        manifest = read_manifest(folder) or {}
        model = manifest["adapter_settings"]["model"]
        priced = not model.startswith(("dashscope/", "volcengine/"))
        assert all((a.cost is not None) == priced for a in answers), folder
        assert all(e["sent"] is not None for e in read_attempts(folder))
    report = run_bpb("report", str(out), "--json", "--bootstrap", "10")
    assert report.returncode == 0, report.stderr
    rows = json.loads(report.stdout)["leaderboard"]
    runs = {r["run"] for r in rows}
    assert len(runs) == 18
    assert any(r.startswith("litellm_gpt-5.4_effort=high") for r in runs)
    marked = {r.split(" [")[0] for r in runs if r.endswith("[dropped: temperature]")}
    assert len(marked) == len(DROPS_TEMPERATURE) and "litellm_gpt-5.5" in marked


def _get(url: str) -> str:
    import urllib.request

    with urllib.request.urlopen(url, timeout=10) as response:
        return str(response.read().decode())
