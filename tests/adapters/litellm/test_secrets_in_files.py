"""No header value or credential-like argument reaches any file a run or its report writes.

Before, a header from ``--model-arg extra_headers.Authorization=...`` or a run file's ``headers``
was masked in run.json but written in clear to attempts.jsonl (litellm's OpenAI chat body
carries the headers), and a header without a secret-looking name was in run.json too.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path

import pytest

from support.fake_openai import fake_server
from support.inprocess import Done, bpb

HIDDEN = ("Bearer-CLIHEADER-0123", "org-FILEHEADER-4567", "PLAINCREDENTIAL-89ab", "Proxy-CLI-cdef")


@pytest.fixture
def cli(capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> Callable[..., Done]:
    for name in ("OPENAI", "ANTHROPIC"):
        monkeypatch.setenv(f"{name}_API_KEY", f"sk-{name.lower()}-bpbtest-0123456789abcdef")
    return functools.partial(bpb, capfd)


def _run_file(path: Path, url: str) -> Path:
    tables = []
    for spec, base in (("litellm:gpt-5.4", f"{url}/v1"), ("litellm:claude-opus-4.5", url)):
        tables.append(
            f'[[adapter]]\nspec = "{spec}"\napi_base = "{base}"\n'
            f'headers = {{"OpenAI-Organization" = "{HIDDEN[1]}"}}\n'
            f'args = {{extra_body = {{vertex_credentials = "{HIDDEN[2]}"}}}}\n'
        )
    path.write_text("[defaults]\ntimeout = 20\n\n" + "\n".join(tables), encoding="utf-8")
    return path


def test_no_header_value_or_credential_appears_in_any_file_of_the_run_or_report(
    cli: Callable[..., Done], dataset: Path, tmp_path: Path
) -> None:
    faults = {"h1_0000/q1": ["400"], "h1_0001/q1": ["500"]}  # error messages are written too
    with fake_server(dataset, {"faults": faults}, tmp_path) as server:
        config = _run_file(tmp_path / "run.toml", server.url)
        done = cli(
            "run", "--data", str(dataset), "--config", str(config),
            "--tasks", "q1", "--out", str(tmp_path / "runs"), "--retries", "1",
            "--model-arg", f"extra_headers.Authorization={HIDDEN[0]}",
            "--model-arg", f"extra_headers.X-Proxy={HIDDEN[3]}",
        )  # fmt: skip
        seen = server.stats()["total"]
    # the 400 stops gpt-5.4 (a setup failure: its message is written to run.json); claude ends
    assert done.returncode == 2 and "stopped, invalid request (400)" in done.stderr, done.stderr
    assert seen >= 8 and not any(secret in done.stderr for secret in HIDDEN)
    report = cli("report", str(tmp_path / "runs"), "--out", str(tmp_path / "report"))
    assert report.returncode == 0, report.stderr
    files = [p for p in tmp_path.rglob("*") if p.is_file() and p.name not in ("run.toml",)]
    files = [p for p in files if p.name != "fake_config.json"]
    assert any(p.name == "attempts.jsonl" for p in files) and any(
        p.suffix == ".html" for p in files
    )
    leaks = [(p, v) for p in files for v in HIDDEN if v.encode() in p.read_bytes()]
    assert leaks == []
    assert not any(v in done.stdout + done.stderr + report.stdout + report.stderr for v in HIDDEN)
