"""Refused, cut, empty and blocked replies on each provider protocol: recorded as such, never as
parse errors, not re-asked, scored wrong and shown by the report per task.

The fake server answers as each API documents it: OpenAI chat's ``refusal`` field and
``finish_reason`` ``content_filter``/``length``, Responses' ``refusal`` item and
``incomplete_details``, Anthropic's ``stop_reason`` ``refusal``/``max_tokens``, Gemini's
``finishReason`` ``SAFETY``/``MAX_TOKENS`` with no content. litellm sends real HTTP to it through
``bpb run``; ``bpb report`` reads the run back (JSON, the terminal and the HTML page), the cut
named as a setting of the run with its cap.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import pytest
from bpb_testing.fakereplies import REFUSAL
from markupsafe import escape

from bpb_core.run_folder import iter_answers, read_attempts
from support.fake_openai import fake_server
from support.inprocess import bpb

KEYS = {
    "OPENAI_API_KEY": "sk-bpbtest-0123456789abcdefSECRET",
    "ANTHROPIC_API_KEY": "sk-ant-bpbtest-0123456789abcdef",
    "GEMINI_API_KEY": "AIzaBPBTEST0123456789abcdef",
    "MOONSHOT_API_KEY": "sk-moon-bpbtest-0123456789abcdef",
}
FAULTS = {"h1_0000": "refusal", "h1_0001": "safety", "h1_0002": "empty", "h3_0000": "length"}
STATUS = {"refusal": "refused", "safety": "refused", "empty": "empty", "length": "cut"}


@dataclass(frozen=True)
class Protocol:
    alias: str
    path: str  # what --api-base adds to the server's root
    said: dict[str, str | None]  # per fault, the provider's own finish word bpb records
    refusal_text: bool  # the protocol carries the refusal's words


PROTOCOLS = {
    "openai-chat": Protocol("kimi-k2.5", "/v1", {"refusal": None, "length": None}, True),
    "openai-responses": Protocol(
        "gpt-5.4-pro", "/v1",
        {"refusal": "completed", "safety": "incomplete: content_filter", "empty": "completed",
         "length": "incomplete: max_output_tokens"}, True),
    "anthropic": Protocol(
        "claude-opus-4.7", "",
        {"refusal": "refusal", "safety": "refusal", "empty": "end_turn", "length": "max_tokens"},
        False),
    "gemini": Protocol(
        "gemini-3-flash-preview", "/v1beta",
        {"refusal": "SAFETY", "safety": "SAFETY", "empty": "STOP", "length": "MAX_TOKENS"},
        False),
}  # fmt: skip


@pytest.mark.parametrize("name", list(PROTOCOLS))
def test_replies_without_an_answer_are_classified_on_every_protocol(
    name: str,
    dataset: Path,
    tmp_path: Path,
    capfd: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    case = PROTOCOLS[name]
    for variable, value in KEYS.items():
        monkeypatch.setenv(variable, value)
    monkeypatch.setenv("COLUMNS", "300")
    faults = {f"{scene}/q1": [fault] for scene, fault in FAULTS.items()}
    run = tmp_path / "run"
    with fake_server(dataset, {"faults": faults}, tmp_path) as server:
        done = bpb(
            capfd, "run", "--data", str(dataset), "--adapter", f"litellm:{case.alias}",
            "--api-base", server.url + case.path, "--out", str(run), "--tasks", "q1",
            "--max-tokens", "300",
        )  # fmt: skip
        counts = server.counts()
    assert done.returncode == 0, done.stderr
    assert all(counts[f"{scene}/q1"] == 1 for scene in FAULTS)  # none re-asked
    folder = next(p for p in run.iterdir() if p.is_dir())
    records = {r.scene_id: r for _, r in iter_answers(folder)}
    for scene, fault in FAULTS.items():
        assert records[scene].status == STATUS[fault], (scene, records[scene].error)
    assert records["h3_0001"].status == "ok"
    cut = records["h3_0000"]
    assert "cut at the token cap" in (cut.error or "") and "300" in (cut.error or "")
    assert "warning:" in done.stdout + done.stderr and "token cap" in done.stdout + done.stderr
    lines = {e["scene_id"]: e for e in read_attempts(folder)}
    for scene, fault in FAULTS.items():
        assert lines[scene]["outcome"] == STATUS[fault]
        assert lines[scene].get("provider_finish") == case.said.get(fault)
    refusal = lines["h1_0000"].get("refusal")
    assert refusal == (REFUSAL if case.refusal_text else None)
    assert (REFUSAL in (records["h1_0000"].error or "")) == case.refusal_text
    line = "replies with no answer, scored wrong (q1 cut 1, empty 1, refused 2); "
    line += cut.error or ""
    report = bpb(capfd, "report", str(folder), "--json", "--bootstrap", "10")
    assert report.returncode == 0, report.stderr
    assert list(json.loads(report.stdout)["unanswered"].values()) == [line]
    shown = bpb(capfd, "report", str(folder), "--out", str(tmp_path / "pages"), "--bootstrap", "10")
    assert shown.returncode == 0, shown.stderr
    assert line in " ".join(shown.stdout.split())  # the terminal, under the leaderboard
    assert str(escape(line)) in (tmp_path / "pages" / "report.html").read_text(encoding="utf-8")
