"""Errors no retry can fix stop an adapter at once, through ``bpb run`` and real HTTP.

A 404 model, an invalid parameter, a spent quota, a refused key: one call, counted at the
server, then one line naming the cause and exit 2. A provider that cannot be reached stops after
the transport budget (5 connection failures in a row), long before a 3,000-pair run would have
retried every pair. The other adapters of a sweep go on.
"""

from __future__ import annotations

import socket
import time
from pathlib import Path

import pytest

from bpb_core.run_folder import iter_answers, read_attempts
from support.fake_openai import fake_server
from support.inprocess import Done, bpb

KEY = "sk-bpbtest-0123456789abcdefSECRET"
MODEL = "litellm:openai/fake-model"


@pytest.fixture(autouse=True)
def _key(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", KEY)
    monkeypatch.setenv("COLUMNS", "300")


def _run(capfd: pytest.CaptureFixture[str], data: Path, out: Path, *args: str) -> Done:
    return bpb(capfd, "run", "--data", str(data), "--out", str(out), *args)


@pytest.mark.parametrize(
    ("fault", "cause"),
    [
        ("404", "not found (404)"),
        ("400", "invalid request (400)"),
        ("quota", "insufficient quota (429)"),
        ("401", "authentication failed (401)"),
        ("403", "permission denied (403)"),
    ],
)
def test_an_error_no_retry_can_fix_costs_one_call(
    fault: str, cause: str, dataset: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    with fake_server(dataset, {"schedule": [fault]}, tmp_path) as server:
        done = _run(
            capfd, dataset, tmp_path / "out", "--adapter", MODEL, "--api-base", server.api_base,
            "--concurrency", "8",
        )  # fmt: skip
        sent = server.stats()["total"]
    assert done.returncode == 2, done.stderr
    assert sent == 1  # not one per pair, nor one per slot of --concurrency
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and cause in errors[0], done.stderr
    assert "17 pairs not sent" in errors[0] and "re-run the same command to resume" in errors[0]
    assert KEY not in done.stdout + done.stderr
    said = " ".join(done.stderr.split())  # the summary names the cause, not the infrastructure
    assert "incomplete: 1 call stopped by a setup error (fix it first) and 17 calls" in said
    with fake_server(dataset, None, tmp_path) as fixed:  # the cause fixed: the same command
        again = _run(
            capfd, dataset, tmp_path / "out", "--adapter", MODEL, "--api-base", fixed.api_base,
            "--concurrency", "8",
        )  # fmt: skip
        resent = fixed.stats()["total"]
    assert again.returncode == 0, again.stderr
    assert resent == 18  # the failed pair and the 17 unsent, nothing twice
    assert all(
        r.status == "ok" for _, r in iter_answers(tmp_path / "out" / "litellm_openai_fake-model")
    )


def _closed_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
    return port  # closed again: connections to it are refused


def test_a_3000_pair_run_at_a_closed_port_exits_2_in_under_30_s(
    dataset: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    started = time.monotonic()
    done = _run(  # 6 scenes x 3 tasks x 167 epochs = 3,006 pairs
        capfd, dataset, out, "--adapter", MODEL, "--api-base",
        f"http://127.0.0.1:{_closed_port()}/v1", "--epochs", "167",
    )  # fmt: skip
    took = time.monotonic() - started
    assert done.returncode == 2, done.stderr
    assert took < 30, took  # the promise; it takes a few seconds here
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "provider unreachable: 5 connection failures" in errors[0]
    assert "--api-base" in errors[0] and "3006 pairs not sent" in errors[0]
    assert "re-run the same command to resume" in errors[0]
    assert len(list(read_attempts(out / "litellm_openai_fake-model"))) == 5  # 5 calls in all
    # each of the 5 was retryable and left for the resume: every pair is still to send


ROUTES = {  # each protocol's model and what --api-base adds to the server's root
    "openai-chat": ("kimi-k2.5", "/v1"),
    "openai-responses": ("gpt-5.4-pro", "/v1"),
    "anthropic": ("claude-opus-4.5", ""),
    "gemini": ("gemini-3-flash-preview", "/v1beta"),
}


@pytest.mark.parametrize("route", list(ROUTES))
def test_a_closed_port_stops_the_adapter_on_every_route_and_the_sweep_goes_on(
    route: str,
    dataset: Path,
    tmp_path: Path,
    capfd: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # litellm reports a refused connection as a 500 on some routes: each must still stop fast
    for variable in ("ANTHROPIC_API_KEY", "GEMINI_API_KEY", "MOONSHOT_API_KEY"):
        monkeypatch.setenv(variable, KEY)
    alias, path = ROUTES[route]
    out = tmp_path / "out"
    done = _run(
        capfd, dataset, out, "--adapter", f"litellm:{alias}", "--adapter", "baseline:stasis",
        "--api-base", f"http://127.0.0.1:{_closed_port()}{path}",
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert f"error: litellm:{alias}: stopped, provider unreachable" in done.stderr
    folder = next(p for p in out.iterdir() if p.name.startswith("litellm_"))
    assert len(list(read_attempts(folder))) == 5
    stasis = [r for _, r in iter_answers(out / "baseline_stasis")]
    assert len(stasis) == 18 and all(r.status == "ok" for r in stasis)
