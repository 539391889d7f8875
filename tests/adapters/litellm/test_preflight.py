"""Preflight: a missing key, an unknown provider or a missing provider module stops ``bpb run``
with exit 2 and one line before a single request is sent; errors that cannot heal are never
retried."""

from __future__ import annotations

import functools
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

from bpb_adapters.litellm_adapter.adapter import _import_litellm
from bpb_adapters.litellm_adapter.errors import map_error
from bpb_core.errors import RetryableModelError, SetupFailure
from support.fake_openai import fake_server
from support.inprocess import Done, bpb

RunBpb = Callable[..., subprocess.CompletedProcess[str] | Done]


def _run(run_bpb: RunBpb, dataset: Path, out: Path, api_base: str, *adapters: str) -> str:
    args = [a for spec in adapters for a in ("--adapter", spec)]
    done = run_bpb("run", "--data", str(dataset), "--out", str(out), "--api-base", api_base, *args)
    assert done.returncode == 2, done.stderr
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, done.stderr
    return lines[0]


@pytest.mark.slow
def test_missing_key_unknown_provider_and_missing_module_send_nothing(
    run_bpb: RunBpb,
    capfd: pytest.CaptureFixture[str],
    dataset: Path,
    tmp_path: Path,
    site: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    here = functools.partial(bpb, capfd)  # in this process; the third, in a fresh one (mcp)
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    monkeypatch.setenv("ANTHROPIC_API_KEY", "sk-ant-bpbtest-0123456789abcdef")
    with fake_server(dataset) as server:
        # The first adapter is fine: nothing of it may be sent either.
        line = _run(here, dataset, tmp_path / "a", server.api_base,
                    "litellm:claude-opus-4.7", "litellm:gpt-5.4-pro")  # fmt: skip
        assert "OPENAI_API_KEY" in line and "gpt-5.4-pro" in line
        line = _run(here, dataset, tmp_path / "b", server.api_base, "litellm:doubao-seed-9")
        assert "no provider" in line and "doubao-seed-9" in line
        monkeypatch.setenv("OPENAI_API_KEY", "sk-bpbtest-0123456789abcdefSECRET")
        (site / "mcp").mkdir(parents=True)  # shadows the installed mcp: as if it were missing
        # (in a process of its own: this one may have imported mcp already)
        (site / "mcp" / "__init__.py").write_text(
            "raise ModuleNotFoundError(\"No module named 'mcp'\", name='mcp')\n"
        )
        line = _run(run_bpb, dataset, tmp_path / "c", server.api_base, "litellm:gpt-5.5-pro")
        assert "'mcp'" in line and "pip install" in line
        assert server.stats()["total"] == 0
    assert not (tmp_path / "a").exists() and not (tmp_path / "c").exists()


def test_import_errors_and_missing_models_are_not_retried() -> None:
    _import_litellm()  # the bundled price map, never a fetch
    from litellm.exceptions import APIConnectionError, NotFoundError

    wrapped = APIConnectionError("OpenAIException - No module named 'mcp'", "openai", "gpt-5.4-pro")
    assert isinstance(map_error(wrapped), SetupFailure)  # stops the adapter: no retry helps
    missing = map_error(NotFoundError("model gpt-9 does not exist", "openai", "gpt-9"))
    assert isinstance(missing, SetupFailure) and missing.cause.startswith("not found (404)")
    dropped = map_error(APIConnectionError("reset by peer", "openai", "x"))
    assert isinstance(dropped, RetryableModelError)
