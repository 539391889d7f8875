"""A model's reply is hostile text: a lone surrogate (JSON's ``"\\udc80"``) in it does not stop
the run, and every file the run writes can be read back."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from bpb_core.model_calls import ModelRequest, ModelResponse
from bpb_core.registry import Registry
from bpb_core.run_folder import AttemptLog, iter_answers, read_attempts
from bpb_core.runner import RetryPolicy, RunOptions, run_eval


@dataclasses.dataclass
class Surrogates:
    """The oracle's answer followed by a lone surrogate, in the text, reasoning and metadata."""

    oracle: object
    name: str = "fake:surrogates"

    async def complete(self, request: ModelRequest) -> ModelResponse:
        right: ModelResponse = await self.oracle.complete(request)  # type: ignore[attr-defined]
        return dataclasses.replace(
            right,
            text=right.text + " \udc80 trailing",
            reasoning="thought \ud800",
            metadata={"note": "m\udfff"},
        )


def test_a_reply_with_a_lone_surrogate_is_stored_and_scored(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    run_dir = tmp_path / "run"
    options = RunOptions(tasks=("q1",), retry=RetryPolicy(max_reasks=0))
    adapter = Surrogates(registry.adapter("baseline:oracle"))
    result = run_eval(dataset, adapter, run_dir, options, registry=registry, spec="fake:s")
    assert result.error is None and result.statuses["q1"]["ok"] == 6
    attempts = list(read_attempts(run_dir))
    assert len(attempts) == 6
    assert all(a["text"].endswith(" \ufffd trailing") for a in attempts)
    assert all(a["reasoning"] == "thought \ufffd" for a in attempts)
    records = [record for _, record in iter_answers(run_dir)]  # pydantic reads them back
    assert [r.status for r in records] == ["ok"] * 6
    assert all(r.metadata == {"note": "m\ufffd"} for r in records)


def test_the_attempts_log_writes_any_string(tmp_path: Path) -> None:
    log = AttemptLog(tmp_path)
    log.append({"text": "a\udc80b", "n": 1})
    log.append({"text": "fine"})
    log.close()
    assert [a["text"] for a in read_attempts(tmp_path)] == ["a\udc80b", "fine"]
