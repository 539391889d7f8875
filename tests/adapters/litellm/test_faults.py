"""The litellm adapter and the runner against a real local HTTP server injecting faults."""

from __future__ import annotations

import base64
from pathlib import Path

import pytest

from bpb_core.model_calls import AdapterOptions
from bpb_core.registry import make_registry
from bpb_core.run_folder import iter_answers, read_attempts
from bpb_core.runner import run_eval
from bpb_core.runner.options import RetryPolicy, RunOptions
from support.fake_openai import fake_server

REGISTRY = make_registry()
MODEL = "litellm:openai/fake-model"
FAST = RetryPolicy(max_retries=3, base_delay=0.02, max_delay=0.5, max_reasks=2)
FAULTS = {
    "h1_0000/q1": ["429", "500"],
    "h1_0000/q2": ["truncated"],
    "h1_0000/q3": ["nonjson"],
    "h1_0001/q1": ["hang"],
    "h1_0001/q2": ["malformed"],
    "h1_0001/q3": ["partial", "partial"],
    "h1_0002/q1": ["cot"],
    "h3_0000/q2": ["length", "length", "length"],
    "h3_0000/q3": ["context"],  # a 400 about this prompt alone: the pair fails, the run goes on
    "h3_0001/q1": ["500", "500", "500", "500", "500"],
    "h3_0001/q2": ["malformed", "malformed", "malformed"],
}


def _run(data: Path, run_dir: Path, api_base: str, **options: object) -> object:
    opts = RunOptions(timeout=1.0, retry=FAST, concurrency=4, **options)  # type: ignore[arg-type]
    return run_eval(
        data,
        MODEL,
        run_dir,
        opts,
        registry=REGISTRY,
        adapter_options=AdapterOptions(api_base=api_base),
    )


@pytest.fixture(scope="module")
def faulty(dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, object]:
    tmp = tmp_path_factory.mktemp("faults")
    mp = pytest.MonkeyPatch()
    mp.setenv("OPENAI_API_KEY", "sk-bpbtest-0123456789abcdefSECRET")
    config = {"faults": FAULTS, "retry_after": 0.3, "hang": 3}
    try:
        with fake_server(dataset, config, tmp) as server:
            result = _run(dataset, tmp / "run", server.api_base)
            first_counts = server.counts()
            server.configure({"faults": {}})
            _run(dataset, tmp / "run", server.api_base)
            yield {
                "run": tmp / "run",
                "result": result,
                "counts": first_counts,
                "after": server.counts(),
                "stats": server.stats(),
            }
    finally:
        mp.undo()


def _records(run_dir: Path) -> dict[str, object]:
    return {f"{r.scene_id}/{r.task}": r for _, r in iter_answers(run_dir)}


def test_every_pair_answered_or_failed_with_reason(faulty: dict, dataset: Path) -> None:
    result = faulty["result"]
    assert (
        sum(sum(v for k, v in c.items() if k != "done_before") for c in result.statuses.values())
        == 18
    )
    attempts = [e for e in read_attempts(faulty["run"])]
    outcomes = {"ok", "parse_error", "cut", "api_error"}
    assert attempts and all(e["outcome"] in outcomes for e in attempts)
    first_pass = {}
    for entry in attempts:
        first_pass.setdefault(f"{entry['scene_id']}/{entry['task']}", []).append(entry)
    # the outcome of the first session, from its attempts
    assert [e["outcome"] for e in first_pass["h1_0000/q1"][:3]] == ["api_error"] * 2 + ["ok"]
    assert first_pass["h1_0000/q1"][0]["retry_in"] == pytest.approx(0.3)  # Retry-After honoured
    assert "RateLimited" in first_pass["h1_0000/q1"][0]["error"]
    assert "ModelTimeout" in first_pass["h1_0001/q1"][0]["error"]
    assert first_pass["h1_0001/q1"][1]["timeout"] == pytest.approx(1.5)  # longer after timeout
    assert (
        first_pass["h1_0001/q2"][1]["escalation"] == 1
        and first_pass["h1_0001/q2"][1]["outcome"] == "ok"
    )
    assert first_pass["h1_0002/q1"][0]["rule"] == "last-valid"
    for key in ("h1_0000/q2", "h1_0000/q3"):
        assert (
            first_pass[key][0]["outcome"] == "api_error" and first_pass[key][1]["outcome"] == "ok"
        )


def test_final_statuses_and_reasons(faulty: dict) -> None:
    records = _records(faulty["run"])
    assert len(records) == 18
    length = records["h3_0000/q2"]  # cut at the cap: recorded as such, never re-asked
    assert length.status == "cut" and length.finish_reason == "length"
    assert "cut at the token cap" in length.error and length.attempts == 1
    assert records["h3_0001/q2"].status == "parse_error"
    ok = records["h1_0002/q2"]
    assert ok.status == "ok" and ok.usage.reasoning_tokens == 20 and ok.usage.cached_tokens == 100
    assert ok.cost is None  # the fake model has no price: unknown, never 0


def test_fail_fast_and_bounded_retries_then_resume(faulty: dict) -> None:
    counts, after = faulty["counts"], faulty["after"]
    assert counts["h3_0000/q3"] == 1  # 400 context_length_exceeded: no retry
    assert counts["h3_0001/q1"] == 4  # 1 + 3 retries, and litellm itself never retried
    assert faulty["result"].api_errors == 2
    records = _records(faulty["run"])
    assert records["h3_0000/q3"].status == "ok" and records["h3_0001/q1"].status == "ok"
    resent = {k for k in after if after[k] != counts.get(k)}
    assert resent == {"h3_0000/q3", "h3_0001/q1"}  # only the api_error pairs were sent again


def test_no_key_or_image_base64_in_any_file(faulty: dict, dataset: Path) -> None:
    image = (dataset / "h1/scene_0000/init.png").read_bytes()
    b64 = base64.b64encode(image).decode()
    assert faulty["stats"]["images"] > 0 and faulty["stats"]["auth_seen"] > 0
    for path in faulty["run"].rglob("*"):
        if path.is_file():
            text = path.read_text()
            assert "0123456789abcdefSECRET" not in text, path
            assert b64[:60] not in text and "data:image" not in text, path
    entry = next(read_attempts(faulty["run"]))
    assert len(entry["image_sha256"]) == 64


def test_max_cost_stops_sending_and_resumes(dataset: Path, tmp_path: Path, secret_key: str) -> None:
    with fake_server(dataset) as server:
        options = AdapterOptions(
            api_base=server.api_base, prices={"openai/fake-model": {"input": 1e-5, "output": 0.0}}
        )
        opts = RunOptions(concurrency=1, max_cost=0.025, retry=FAST, timeout=5)
        result = run_eval(
            dataset, MODEL, tmp_path / "run", opts, registry=REGISTRY, adapter_options=options
        )
        # each call costs 0.01 and reserves its input counted with a margin: the third would
        # pass the cap, so it is not sent (the soft cap used to send it and spend 0.03)
        assert result.stopped == "max-cost" and result.cost == pytest.approx(0.02)
        assert server.stats()["total"] == 2 and result.not_sent == 16
        assert result.budget["spent"] == pytest.approx(0.02) and result.budget["cap"] == 0.025
        again = run_eval(
            dataset,
            MODEL,
            tmp_path / "run",
            RunOptions(retry=FAST, timeout=5),
            registry=REGISTRY,
            adapter_options=options,
        )
        assert again.stopped is None and server.stats()["total"] == 18
        assert sum(c["done_before"] for c in again.statuses.values()) == 2


def test_auth_failure_stops_the_run(dataset: Path, tmp_path: Path, secret_key: str) -> None:
    with fake_server(dataset, {"faults": {"*/q1": ["401"] * 10}}, tmp_path) as server:
        opts = RunOptions(concurrency=1, retry=FAST, timeout=5, tasks=("q1", "q2"))
        result = run_eval(
            dataset,
            MODEL,
            tmp_path / "run",
            opts,
            registry=REGISTRY,
            adapter_options=AdapterOptions(api_base=server.api_base),
        )
        assert result.stopped == "setup" and "AuthenticationError" in (result.error or "")
        assert server.stats()["total"] == 1 and result.not_sent == 11  # 6 scenes x 2 tasks
        assert secret_key not in (result.error or "")
