"""``bpb report`` on hostile run folders: odd names and manifests are shown as text, never stop
the report."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from bpb_core.registry import Registry
from bpb_core.web.viewer import Viewer
from support import inprocess

BPB = str(Path(sys.executable).with_name("bpb"))


def bpb(*args: str) -> subprocess.CompletedProcess[str]:
    """``bpb ARGS`` as a process: its standard output encodes strictly (pytest's capture
    replaces what it cannot encode, and would hide a lone surrogate printed)."""
    env = {**os.environ, "COLUMNS": "160"}
    return subprocess.run([BPB, *args], capture_output=True, text=True, env=env, timeout=180)


def test_lone_surrogates_in_run_json_and_a_folder_name_are_shown_as_u_fffd(
    runs: Path, tmp_path: Path, registry: Registry
) -> None:
    manifest_path = runs / "litellm_model" / "run.json"
    manifest = json.loads(manifest_path.read_text())
    manifest |= {"adapter": "litellm:m\udc80", "model_id": "m\ud800<b>"}
    manifest_path.write_text(json.dumps(manifest))  # ASCII, with "\udc80" escapes
    for answer in (runs / "litellm_model").glob("h*/scene_*/*.json"):  # the run's adapter, as
        record = json.loads(answer.read_text())  # read (an answer file cannot hold a surrogate)
        answer.write_text(json.dumps(record | {"adapter": "litellm:m\ufffd"}))
    odd = os.fsdecode(os.fsencode(runs / "baseline_stasis") + b"\xff")  # not UTF-8
    os.rename(runs / "baseline_stasis", odd)
    done = bpb("report", str(runs), "--out", str(tmp_path / "out"), "--bootstrap", "10")
    assert done.returncode == 0, done.stderr
    page = (tmp_path / "out" / "report.html").read_text(encoding="utf-8")
    assert "litellm:m\ufffd" in page and "m\ufffd&lt;b&gt;" in page
    assert "baseline_stasis\ufffd" in page
    labels = [run.label for run in Viewer.load([runs], registry).results.runs]
    assert "baseline_stasis\ufffd" in labels


def test_dollar_signs_in_run_names_and_titles_are_drawn_as_text(
    runs: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import pandas as pd

    from bpb_core.report.charts import leaderboard_figure, png as to_png

    os.rename(runs / "litellm_model", runs / "price $\\frac{$ run")  # matplotlib math: invalid
    monkeypatch.setenv("COLUMNS", "160")
    done = inprocess.bpb(
        capfd, "report", str(runs), "--out", str(tmp_path / "out"), "--bootstrap", "10"
    )
    assert done.returncode == 0, done.stderr
    assert "price $\\frac{$ run" in (tmp_path / "out" / "report.html").read_text()
    board = pd.DataFrame({"run": ["a$", "b$^{$"], "baseline": [False, True], "m": [0.5, 0.2]})
    png = to_png(leaderboard_figure(board, ["m"], titles={"m": "a plugin's $\\frac{$ title"}))
    assert png.startswith(b"\x89PNG")
