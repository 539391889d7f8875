"""Every option sent to the provider is part of a run's identity: the output cap too.

Before, a run made with no ``--max-tokens`` and resumed with ``--max-tokens 20000`` sent nothing,
kept the uncapped answers and rewrote run.json to say 20000."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bpb_core.errors import BadInput
from bpb_core.registry import Registry
from bpb_core.run_folder import iter_answers
from bpb_core.runner import RunOptions, run_eval


def _run(data: Path, run_dir: Path, registry: Registry, **kw: object) -> None:
    adapter = registry.adapter("baseline:oracle")
    options = RunOptions(concurrency=1, **kw)  # type: ignore[arg-type]
    run_eval(data, adapter, run_dir, options, registry=registry, spec="baseline:oracle")


@pytest.mark.parametrize(("first", "then"), [(None, 20000), (4096, None), (4096, 8192)])
def test_a_resume_with_another_output_cap_is_refused_naming_it(
    dataset: Path, tmp_path: Path, registry: Registry, first: int | None, then: int | None
) -> None:
    run_dir = tmp_path / "run"
    _run(dataset, run_dir, registry, max_tokens=first, limit=1)
    before = (run_dir / "run.json").read_bytes()
    shown = {None: "no cap"}
    pattern = rf"max_tokens: this folder holds a run with {shown.get(first, first)}, not "
    with pytest.raises(BadInput, match=pattern + str(shown.get(then, then))):
        _run(dataset, run_dir, registry, max_tokens=then)
    assert (run_dir / "run.json").read_bytes() == before  # nothing rewritten
    assert len(list(iter_answers(run_dir))) == 6  # nothing sent


def test_the_same_cap_resumes_and_a_folder_made_before_the_cap_was_recorded_too(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    run_dir = tmp_path / "run"
    _run(dataset, run_dir, registry, max_tokens=4096, limit=1)
    _run(dataset, run_dir, registry, max_tokens=4096)
    assert len(list(iter_answers(run_dir))) == 18
    old = tmp_path / "old"
    _run(dataset, old, registry, limit=1)
    manifest = json.loads((old / "run.json").read_text())
    del manifest["options"]["max_tokens"]  # as an older bpb wrote it
    (old / "run.json").write_text(json.dumps(manifest))
    _run(dataset, old, registry, max_tokens=4096)
    assert len(list(iter_answers(old))) == 18
