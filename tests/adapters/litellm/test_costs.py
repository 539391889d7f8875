"""Cost you can trust: ``--dry-run`` estimates per provider's image rule with a dollar figure,
and ``--max-cost`` refuses adapters it cannot price."""

from __future__ import annotations

import functools
import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from bpb_adapters.litellm_adapter.prices import image_tokens
from support.fake_openai import fake_server
from support.inprocess import Done, bpb
from support.runner_scenes import png_bytes

RunBpb = Callable[..., Done]
BPB = str(Path(sys.executable).with_name("bpb"))


@pytest.fixture
def run_bpb(site: Path, capfd: pytest.CaptureFixture[str]) -> RunBpb:
    """``bpb ARGS`` in this process, ``site`` first on ``sys.path`` (conftest's ``run_bpb``
    runs the console script)."""
    return functools.partial(bpb, capfd, site=site)


def test_image_rules_per_provider() -> None:
    small = png_bytes(1, (64, 32))
    assert image_tokens("openai", small) == 85 + 170  # one 512 tile
    assert image_tokens("anthropic", small) == 3  # 64 * 32 / 750, rounded up
    assert image_tokens("gemini", small) == 258  # within 384 x 384
    wide = png_bytes(1, (2000, 1000))
    assert image_tokens("anthropic", wide) == 1568 * 784 // 750 + 1  # long edge scaled to 1568
    assert image_tokens("gemini", wide) == 258 * 3 * 2  # 768-pixel tiles
    assert image_tokens("dashscope", wide) == image_tokens("openai", wide)


def _table(stdout: str) -> dict[str, list[str]]:
    rows = [[c.strip() for c in line.split("│")[1:-1]] for line in stdout.splitlines()]
    return {f"{r[0]}/{r[1]}": r[2:] for r in rows if len(r) == 9 and r[0].startswith("litellm")}


def test_dry_run_shows_tokens_and_dollars_per_adapter_without_keys(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    for name in ("OPENAI", "ANTHROPIC", "GEMINI", "DASHSCOPE"):
        monkeypatch.delenv(f"{name}_API_KEY", raising=False)
    adapters = ["gpt-5.4", "claude-opus-4.7", "gemini-3-flash-preview", "qwen3.6-plus"]
    args = [a for m in adapters for a in ("--adapter", f"litellm:{m}")]
    with fake_server(dataset) as server:
        done = run_bpb("run", "--data", str(dataset), "--out", str(tmp_path), "--tasks", "q1",
                       "--dry-run", "--api-base", server.api_base, *args)  # fmt: skip
        assert server.stats()["total"] == 0
    assert done.returncode == 0, done.stderr
    table = _table(done.stdout)
    tokens = {
        key.split(":")[1].split("/")[0]: int(v[2].replace(",", "")) for key, v in table.items()
    }
    # Same prompts; the image counts 255 (OpenAI tiles), 3 (Anthropic) or 258 (Gemini) tokens.
    assert tokens["gemini-3-flash-preview"] > tokens["claude-opus-4.7"]
    assert all(v[0] == "6" for v in table.values())  # 6 scenes, nothing done before
    costs = {key.split(":")[1].split("/")[0]: v[3] for key, v in table.items()}
    assert costs["qwen3.6-plus"] == "no price" and costs["gpt-5.4"].startswith("$")
    assert float(costs["claude-opus-4.7"][1:]) > 0
    # no --max-tokens: the output cap is the model's limit (litellm model info), 128,000 tokens
    # for gpt-5.4 at $15 per million
    assert table["litellm:gpt-5.4/q1"][5] == f"${6 * 128_000 * 15e-6:,.4f}"
    assert "the model's output limit 128,000" in done.stdout


def test_max_cost_refuses_unpriced_adapters_unless_priced_or_allowed(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("DASHSCOPE_API_KEY", "sk-dash-bpbtest-0123456789abcdef")
    with fake_server(dataset) as server:
        base = ["run", "--data", str(dataset), "--tasks", "q1", "--limit", "1", "--max-cost", "1",
                "--max-tokens", "100",
                "--api-base", server.api_base, "--adapter", "litellm:qwen3.6-plus"]  # fmt: skip
        refused = run_bpb(*base, "--out", str(tmp_path / "a"))
        assert refused.returncode == 2 and "qwen3.6-plus" in refused.stderr
        assert "--allow-unpriced" in refused.stderr and server.stats()["total"] == 0
        allowed = run_bpb(*base, "--out", str(tmp_path / "b"), "--allow-unpriced")
        assert allowed.returncode == 0, allowed.stderr
        prices = tmp_path / "prices.json"
        prices.write_text(json.dumps({"qwen3.6-plus": {"input": 1e-6, "output": 4e-6}}))
        # a process of its own: litellm keeps one price map per process, and this one's tests
        # must see qwen3.6-plus unpriced
        command = [BPB, *base, "--out", str(tmp_path / "c"), "--prices", str(prices)]
        priced = subprocess.run(command, capture_output=True, text=True, timeout=120)
        assert priced.returncode == 0, priced.stderr
    manifest = json.loads(next((tmp_path / "c").rglob("run.json")).read_text())
    assert manifest["last_session"]["cost"] == pytest.approx(2 * (1000 * 1e-6 + 50 * 4e-6))


@pytest.mark.parametrize(
    ("source", "value", "field"),
    [
        ("prices.json", "NaN", "--prices: openai/fake.input"),
        ("prices.json", "Infinity", "--prices: openai/fake.input"),
        ("run.toml", "nan", "adapter 1.price.input"),
        ("run.toml", "inf", "adapter 1.price.input"),
    ],
)
def test_non_finite_price_is_refused_before_any_call(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, secret_key: str,
    source: str, value: str, field: str,
) -> None:  # fmt: skip
    # A NaN price made every cost NaN and --max-cost never stop (NaN >= cap is false).
    out = tmp_path / "out"
    with fake_server(dataset) as server:
        path = tmp_path / source
        if source.endswith(".json"):
            path.write_text(f'{{"openai/fake": {{"input": {value}, "output": 1e-6}}}}')
            given = ["--adapter", "litellm:openai/fake", "--prices", str(path)]
        else:
            path.write_text(f'[[adapter]]\nspec = "litellm:openai/fake"\n'
                            f"price = {{input = {value}, output = 1e-6}}\n")  # fmt: skip
            given = ["--config", str(path)]
        done = run_bpb("run", "--data", str(dataset), "--out", str(out), "--max-cost", "0.01",
                       "--api-base", server.api_base, *given)  # fmt: skip
        assert server.stats()["total"] == 0
    assert done.returncode == 2, done.stderr
    line = done.stderr.strip()
    assert "\n" not in line and str(path) in line and field in line, line
    assert "finite number >= 0" in line and not out.exists()


def test_a_price_table_missing_the_model_is_said_before_the_run(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, secret_key: str
) -> None:
    # keyed by a short name, the table priced nothing and the live cost read "$?" all run
    for key, said in (("fake", True), ("openai/fake", False)):
        prices = tmp_path / f"{key.replace('/', '_')}.json"
        prices.write_text(json.dumps({key: {"input": 1e-6, "output": 1e-6}}))
        with fake_server(dataset) as server:
            done = run_bpb(
                "run", "--data", str(dataset), "--tasks", "q1", "--limit", "1",
                "--api-base", server.api_base, "--adapter", "litellm:openai/fake",
                "--prices", str(prices), "--out", str(tmp_path / prices.stem),
            )  # fmt: skip
        assert done.returncode == 0, done.stderr
        note = f"--prices: no price for litellm:openai/fake (its keys: {key})"
        assert (note in done.stderr) == said, done.stderr
