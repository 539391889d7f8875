"""A hard ``--max-cost``: against a local server that bills every reply its whole output cap, at
concurrency 8, what the server was sent never costs more than the cap: one model, two models,
three sessions of one folder; and the estimates a researcher budgets with (``--dry-run``,
``--pilot``)."""

from __future__ import annotations

import functools
import json
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from bpb_core.runner.budget import past_spending
from support.fake_openai import FakeServer, fake_server
from support.inprocess import Done, bpb

RunBpb = Callable[..., Done]
IN, OUT, MAX_TOKENS = 1e-6, 4e-6, 200
PER_CALL = 1000 * IN + MAX_TOKENS * OUT  # the server reports 1000 input tokens, bills the cap
PRICES = {f"openai/capped-{n}": {"input": IN, "output": OUT} for n in "abc"}


@pytest.fixture
def run_bpb(capfd: pytest.CaptureFixture[str]) -> RunBpb:
    return functools.partial(bpb, capfd)


@pytest.fixture(scope="module")
def server(dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[FakeServer]:
    tmp = tmp_path_factory.mktemp("billing")
    with fake_server(dataset, {"bill_max_tokens": True, "latency": 0.15}, tmp) as running:
        yield running


def _sent(server: FakeServer, before: int) -> float:
    """USD of the requests the server received since it had ``before``."""
    return (server.stats()["total"] - before) * PER_CALL


def _run(
    run_bpb: RunBpb, dataset: Path, out: Path, server: FakeServer, *args: str
) -> tuple[Done, float]:
    prices = out.parent / "prices.json"
    prices.write_text(json.dumps(PRICES))
    before = server.stats()["total"]
    done = run_bpb("run", "--data", str(dataset), "--out", str(out), "--concurrency", "8",
                   "--max-tokens", str(MAX_TOKENS), "--prices", str(prices),
                   "--api-base", server.api_base, *args)  # fmt: skip
    return done, _sent(server, before)


def _budget(out: Path, model: str) -> dict[str, object]:
    manifest = json.loads((out / f"litellm_openai_capped-{model}" / "run.json").read_text())
    budget: dict[str, object] = manifest["last_session"]["budget"]
    return budget


def test_one_model_never_sends_more_than_the_cap(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, server: FakeServer, secret_key: str
) -> None:
    cap = 0.01
    done, sent = _run(run_bpb, dataset, tmp_path / "out", server,
                      "--adapter", "litellm:openai/capped-a", "--max-cost", str(cap))  # fmt: skip
    assert done.returncode == 1, done.stderr  # pairs left unsent by the cap
    assert 0 < sent <= cap  # the old soft cap sent 8 in flight past it
    assert sent > cap - 2 * PER_CALL  # and the cap is used, not wasted on reservations
    budget = _budget(tmp_path / "out", "a")
    assert budget["command_spent"] == pytest.approx(sent)
    assert budget["reserved"] == 0 and budget["command_left"] == pytest.approx(cap - sent)
    kept = budget["kept_by_cap"]
    assert isinstance(kept, list) and len(kept) == 18 - round(sent / PER_CALL)
    assert "the cap kept" in done.stderr and "higher --max-cost" in done.stderr
    report = run_bpb("report", str(tmp_path / "out"), "--out", str(tmp_path / "report"))
    assert report.returncode == 0, report.stderr
    page = (tmp_path / "report" / "report.html").read_text()
    assert "Spending and the cost cap" in page and str(kept[0]) in page


def test_two_models_share_one_cap(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, server: FakeServer, secret_key: str
) -> None:
    cap = 0.045  # more than one model's 18 pairs cost: the second gets what the first left
    done, sent = _run(run_bpb, dataset, tmp_path / "out", server, "--max-cost", str(cap),
                      "--adapter", "litellm:openai/capped-a",
                      "--adapter", "litellm:openai/capped-b")  # fmt: skip
    assert done.returncode == 1, done.stderr
    assert 18 * PER_CALL < sent <= cap
    first, second = _budget(tmp_path / "out", "a"), _budget(tmp_path / "out", "b")
    assert first["spent"] == pytest.approx(18 * PER_CALL) and first["kept_by_cap"] == []
    assert second["command_spent"] == pytest.approx(sent)
    assert isinstance(second["spent"], float) and 0 < second["spent"] <= cap - 18 * PER_CALL


def test_three_sessions_count_what_earlier_ones_spent(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, server: FakeServer, secret_key: str
) -> None:
    cap, out, total = 0.008, tmp_path / "out", 0.0
    adapter = ("--adapter", "litellm:openai/capped-c")
    for _ in range(3):
        done, sent = _run(run_bpb, dataset, out, server, *adapter, "--max-cost", str(cap))
        assert done.returncode == 1, done.stderr
        total += sent
    assert 0 < total <= cap  # before: each session spent its own cap
    assert past_spending(out / "litellm_openai_capped-c") == pytest.approx(total)
    # a raised cap sends more, counting the earlier spending
    done, sent = _run(run_bpb, dataset, out, server, *adapter, "--max-cost", str(2 * cap))
    assert sent > 0 and total + sent <= 2 * cap


def test_reservation_of_a_killed_session_counts_in_full(tmp_path: Path) -> None:
    ledger = tmp_path / "spending.jsonl"
    lines = [
        {"hold": "a", "usd": 0.5, "pair": "h1_0000/q1"},
        {"settle": "a", "usd": 0.1, "pair": "h1_0000/q1", "basis": "reply"},
        {"hold": "b", "usd": 0.7, "pair": "h1_0001/q1"},  # in flight when the session died
    ]
    ledger.write_text("".join(json.dumps(line) + "\n" for line in lines) + '{"hold": "c", "us')
    assert past_spending(tmp_path) == pytest.approx(0.8)


def test_capped_model_without_output_limit_is_refused_before_any_call(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, server: FakeServer, secret_key: str
) -> None:
    prices = tmp_path / "prices.json"
    prices.write_text(json.dumps(PRICES))
    before = server.stats()["total"]
    done = run_bpb("run", "--data", str(dataset), "--out", str(tmp_path / "out"),
                   "--max-cost", "1", "--prices", str(prices), "--api-base", server.api_base,
                   "--adapter", "litellm:openai/capped-a")  # fmt: skip
    assert done.returncode == 2 and server.stats()["total"] == before
    line = done.stderr.strip()
    assert "\n" not in line and "capped-a" in line and "--max-tokens" in line, line


def _rows(stdout: str) -> dict[str, list[str]]:
    rows = [[c.strip() for c in line.split("│")[1:-1]] for line in stdout.splitlines()]
    return {f"{r[0]}/{r[1]}": r[2:] for r in rows if len(r) == 9}


def test_dry_run_gives_output_cost_typical_and_at_the_cap(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, server: FakeServer
) -> None:
    before = server.stats()["total"]
    done, _ = _run(run_bpb, dataset, tmp_path / "out", server, "--dry-run", "--tasks", "q1",
                   "--adapter", "litellm:openai/capped-a")  # fmt: skip
    assert done.returncode == 0 and server.stats()["total"] == before
    row = _rows(done.stdout)["litellm:openai/capped-a/q1"]
    assert row[0] == "6"  # calls
    assert row[5] == f"${6 * MAX_TOKENS * OUT:.4f}"  # every call at its cap
    assert "--max-tokens 200" in done.stdout and "assumed" in done.stdout  # the basis


def test_pilot_sends_n_pairs_projects_and_is_never_paid_again(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, server: FakeServer, secret_key: str
) -> None:
    out = tmp_path / "out"
    args = ("--adapter", "litellm:openai/capped-b", "--tasks", "q1,q2")
    done, sent = _run(run_bpb, dataset, out, server, "--pilot", "4", *args)
    assert done.returncode == 0, done.stderr
    assert sent == pytest.approx(4 * PER_CALL)
    rows = _rows(done.stdout)
    assert rows["litellm:openai/capped-b/q1"][:2] == ["4", "2"]  # 4 calls left, 2 done
    assert rows["litellm:openai/capped-b/q1"][6] == f"${4 * PER_CALL:.4f}"  # real usage x 4
    assert "real usage" in done.stdout
    again, sent = _run(run_bpb, dataset, out, server, "--pilot", "4", *args)
    assert again.returncode == 0 and sent == 0
    full, sent = _run(run_bpb, dataset, out, server, *args)
    assert full.returncode == 0 and sent == pytest.approx(8 * PER_CALL)  # the rest, once
