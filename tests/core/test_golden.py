"""Every command gives the same dataset bytes and the same scores as bpb did before the plugin
boundary moved (issue 8): tests/fixtures/golden was made with the earlier code (see its README)
and is regenerated here through the real ``bpb`` command.

Files are compared byte for byte when the libraries that shape them (Pillow, matplotlib, numpy,
pydantic) are the versions recorded in the fixture's manifest; after an upgrade of one of them,
JSON and CSV files are still compared exactly and images pixel for pixel.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from PIL import Image, ImageChops

from support.paths import FIXTURES

GOLDEN = FIXTURES / "golden"
BPB = str(Path(sys.executable).with_name("bpb"))
VOLATILE = {"latency"}  # measured wall time of a baseline's answer


def bpb(*args: str, cwd: Path) -> str:
    env = {**os.environ, "COLUMNS": "200"}
    done = subprocess.run(
        [BPB, *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=300
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The golden commands run again in a scratch folder."""
    root = tmp_path_factory.mktemp("golden")
    bpb("generate", "--out", "data", "--per-horizon", "3", "--horizons", "1,3", "--seed", "7",
        "--workers", "2", cwd=root)  # fmt: skip
    bpb("run", "--data", "data", "--out", "runs", cwd=root)
    bpb("run", "--data", "data", "--out", "runs", "--adapter", "echo:prompt",
        "--adapter", "echo:upper", cwd=root)  # fmt: skip
    (root / "report.json").write_text(bpb("report", "runs", "--json", cwd=root))
    bpb("report", "runs", "--out", "report", cwd=root)
    for name, extra in (
        ("", ()),
        ("_stability", ("--stability",)),
        ("_pymunk", ("--simulator", "pymunk")),
    ):
        (root / f"simulate{name}.jsonl").write_text(bpb("simulate", *extra, "data", cwd=root))
    return root


def _same_libraries(made: Path) -> bool:
    old = json.loads((GOLDEN / "data" / "dataset.json").read_text())["versions"]
    new = json.loads((made / "dataset.json").read_text())["versions"]
    return bool(old == new)


def _files(root: Path) -> list[str]:
    return sorted(p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file())


def test_generate_gives_the_same_dataset(work: Path) -> None:
    made, golden = work / "data", GOLDEN / "data"
    assert _files(made) == _files(golden)
    if _same_libraries(made):
        assert [
            f for f in _files(golden) if (made / f).read_bytes() != (golden / f).read_bytes()
        ] == []
        return
    for name in _files(golden):
        if name.endswith(".png"):
            with Image.open(made / name) as a, Image.open(golden / name) as b:
                assert ImageChops.difference(a.convert("RGB"), b.convert("RGB")).getbbox() is None
        elif name.endswith((".json", ".csv")) and name != "dataset.json":
            assert (made / name).read_bytes() == (golden / name).read_bytes(), name
    old, new = (json.loads((d / "dataset.json").read_text()) for d in (golden, made))
    for key in ("versions", "dataset_hash", "files"):
        old.pop(key), new.pop(key)
    assert new == old


def test_simulate_prints_the_same_ground_truth(work: Path) -> None:
    for name in ("simulate.jsonl", "simulate_stability.jsonl", "simulate_pymunk.jsonl"):
        assert (work / name).read_text() == (GOLDEN / name).read_text(), name


def _answers(run: Path) -> dict[str, dict[str, Any]]:
    out = {}
    for path in sorted(run.rglob("q*.json")):
        record = json.loads(path.read_text())
        out[path.relative_to(run).as_posix()] = {
            k: v for k, v in record.items() if k not in VOLATILE
        }
    return out


def test_runs_give_the_same_answers_and_scores(work: Path) -> None:
    golden_runs = sorted(p.name for p in (GOLDEN / "runs").iterdir())
    assert sorted(p.name for p in (work / "runs").iterdir() if p.is_dir() and p.name != "data") \
        == golden_runs  # fmt: skip
    for name in golden_runs:
        made, golden = work / "runs" / name, GOLDEN / "runs" / name
        assert _answers(made) == _answers(golden), name
        new, old = pd.read_csv(made / "scores.csv"), pd.read_csv(golden / "scores.csv")
        if _same_libraries(work / "data"):
            assert (made / "scores.csv").read_bytes() == (golden / "scores.csv").read_bytes()
        pd.testing.assert_frame_equal(new.drop(columns="dataset"), old.drop(columns="dataset"))


def _rows(records: list[dict[str, Any]], key: tuple[str, ...]) -> dict[tuple[Any, ...], Any]:
    return {tuple(r[k] for k in key): r for r in records}


def _as_old(new: list[dict[str, Any]], old: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """``new`` rows cut to the fields the golden rows have (reports gained columns since, such
    as completeness; the numbers they had must not change)."""
    fields = list(old[0]) if old else []
    return [{k: row[k] for k in fields} for row in new]


def test_report_json_gives_the_same_numbers(work: Path) -> None:
    new, old = (json.loads(p.read_text()) for p in (work / "report.json", GOLDEN / "report.json"))
    assert _as_old(new["leaderboard"], old["leaderboard"]) == old["leaderboard"]
    stable = _as_old(new["stable"], old["stable"])
    assert _rows(stable, ("run",)) == _rows(old["stable"], ("run",))
    key = ("run", "metric")
    assert _rows(new["bootstrap"], key).keys() == _rows(old["bootstrap"], key).keys()
    for row_key, row in _rows(old["bootstrap"], key).items():
        mine = _rows(new["bootstrap"], key)[row_key]
        for column in ("estimate", "lo", "hi", "scenes"):
            assert mine[column] == pytest.approx(row[column], rel=1e-12, abs=1e-15), row_key
    stasis = _as_old(new["diagnostics"]["stasis"], old["diagnostics"]["stasis"])
    assert _rows(stasis, ("run",)) == _rows(old["diagnostics"]["stasis"], ("run",))
    assert _as_old(new["stable_exclusions"], old["stable_exclusions"]) == old["stable_exclusions"]


# Old table file -> the table(s) that hold it now (the diagnostics moved to the task plugins).
MOVED = {
    "confusion.csv": ("q1_confusion.csv", "q2_confusion.csv"),
    "distance.csv": ("q3_distance.csv",),
    "distance_by_horizon.csv": ("q3_distance_by_horizon.csv",),
    "tolerance.csv": ("q3_tolerance.csv",),
}
KEYS = ("run", "task", "unit", "horizon", "metric", "tolerance", "a", "b")


@pytest.mark.parametrize("name", sorted(p.name for p in (GOLDEN / "tables").iterdir()))
def test_report_tables_give_the_same_numbers(work: Path, name: str) -> None:
    old = pd.read_csv(GOLDEN / "tables" / name)
    sources = MOVED.get(name, (name,))
    new = pd.concat([pd.read_csv(work / "report" / "tables" / s) for s in sources])
    assert set(old.columns) <= set(new.columns)  # new columns (completeness) are allowed
    new = new[list(old.columns)]
    keys = [k for k in KEYS if k in old.columns]
    old, new = (f.sort_values(keys).reset_index(drop=True) for f in (old, new))
    pd.testing.assert_frame_equal(new, old, check_dtype=False, rtol=1e-12)
