"""A hand-edited ``dataset.json``: ``bpb run`` and ``bpb simulate`` read its family, config and
hash, and every edit that breaks one of them (or any field of a generated manifest) is one line
naming the file and the field, exit 2, with nothing asked or printed."""

from __future__ import annotations

import hashlib
import json
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bpb_core.dataset import load_dataset

BPB = str(Path(sys.executable).with_name("bpb"))


def edit(change: Callable[[dict[str, Any]], object]) -> Callable[[Path], None]:
    def apply(path: Path) -> None:
        manifest = json.loads(path.read_text())
        change(manifest)
        path.write_text(json.dumps(manifest, indent=2, sort_keys=True) + "\n")

    return apply


def text(old: str, new: str) -> Callable[[Path], None]:
    def apply(path: Path) -> None:
        assert old in path.read_text()
        path.write_text(path.read_text().replace(old, new, 1))

    return apply


def write(content: str) -> Callable[[Path], None]:
    return lambda path: path.write_text(content)


def folder(path: Path) -> None:
    path.unlink()
    path.mkdir()


NOT_FINITE = "not a finite number (NaN and infinity are not JSON)"
EDITS: dict[str, tuple[Callable[[Path], None], str]] = {
    "empty": (write(""), "cannot read dataset manifest: Expecting value"),
    "a list": (write("[1, 2]\n"), "not a dataset manifest: a JSON object ({...}) expected"),
    "null": (write("null\n"), "not a dataset manifest: a JSON object ({...}) expected, not null"),
    "a folder": (folder, "cannot read dataset manifest: Is a directory"),
    "config a list": (
        edit(lambda m: m.update(config=[1])),
        "config: an object of the scene family's settings expected, not a list",
    ),
    "no config": (edit(lambda m: m.pop("config")), "config: Field required"),
    "family a number": (
        edit(lambda m: m["config"].update(family=3)),
        "config.family: a scene family name expected, not 3",
    ),
    "balls a word": (
        edit(lambda m: m["config"].update(balls="seven")),
        "config: balls: Input should be a valid integer",
    ),
    "config junk": (
        edit(lambda m: m["config"].update(junk=1)),
        "config: junk: Extra inputs are not permitted",
    ),
    "mu NaN": (text('"mu": 0.002', '"mu": NaN'), f"config.physics.mu: {NOT_FINITE}"),
    "seed NaN": (text('"seed": 11', '"seed": NaN'), f"seed: {NOT_FINITE}"),
    "seed a word": (edit(lambda m: m.update(seed="x")), "seed: Input should be a valid integer"),
    # no coercion: "11" is no seed, "yes" no flag, true no count of balls
    "seed a numeral": (
        edit(lambda m: m.update(seed="11")),
        "seed: Input should be a valid integer",
    ),
    "images a word": (
        edit(lambda m: m.update(images="yes")),
        "images: Input should be a valid boolean",
    ),
    "scenes true": (
        edit(lambda m: m["summary"]["h1"].update(scenes=True)),
        "summary.h1.scenes: Input should be a valid integer",
    ),
    "balls true": (
        edit(lambda m: m["config"].update(balls=True)),
        "config: balls: Input should be a valid integer",
    ),
    "no summary": (edit(lambda m: m.pop("summary")), "summary: Field required"),
    "hash a number": (
        edit(lambda m: m.update(dataset_hash=5)),
        "dataset_hash: a string expected, not 5",
    ),
}


@pytest.fixture
def copy(small_dataset: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(small_dataset, tmp_path / "ds"))


@pytest.mark.parametrize(("change", "named"), EDITS.values(), ids=EDITS.keys())
def test_an_edited_manifest_is_one_line_naming_the_file_and_field(
    copy: Path, tmp_path: Path, change: Callable[[Path], None], named: str
) -> None:
    change(copy / "dataset.json")
    out = tmp_path / "runs"
    commands = [
        ["run", "--data", str(copy), "--adapter", "baseline:stasis", "--out", str(out),
         "--tasks", "q1", "--limit", "1"],
        ["simulate", str(copy / "h1" / "scene_0000")],
    ]  # fmt: skip
    for command in commands:
        done = subprocess.run([BPB, *command], capture_output=True, text=True, timeout=120)
        assert done.returncode == 2, (command[0], done.stdout, done.stderr)
        assert done.stdout == ""
        (line,) = done.stderr.strip().splitlines()
        assert line.startswith(f"error: {copy}/dataset.json: {named}"), (command[0], line)
    assert not out.exists() or not list(out.rglob("q1.json"))


def test_simulate_names_a_simulator_the_manifest_names_but_is_not_installed(
    copy: Path,
) -> None:
    edit(lambda m: m["config"].update(simulator="nope"))(copy / "dataset.json")
    done = subprocess.run([BPB, "simulate", str(copy)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stdout == ""
    (line,) = done.stderr.strip().splitlines()
    assert line.startswith(
        f"error: {copy}/dataset.json: config: names simulator 'nope', which is not installed "
        "(installed: analytic"
    )
    assert line.endswith("; or choose one with --simulator")
    ok = subprocess.run([BPB, "simulate", str(copy), "--simulator", "analytic"],
                        capture_output=True, text=True, timeout=120)  # fmt: skip
    assert ok.returncode == 0 and len(ok.stdout.splitlines()) == 6


def _run_q1(data: Path, out: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [BPB, "run", "--data", str(data), "--adapter", "baseline:stasis", "--out", str(out),
         "--tasks", "q1", "--limit", "1"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip


def test_a_manifest_edited_after_generation_is_refused_before_the_run_folder(
    copy: Path, tmp_path: Path
) -> None:
    # An edit that keeps every field valid (here the seed) was run, and run.json recorded the
    # manifest's stale dataset_hash: two different datasets looked the same in the results.
    manifest = copy / "dataset.json"
    recorded = json.loads(manifest.read_text())["dataset_hash"]
    edit(lambda m: m.update(seed=m["seed"] + 1))(manifest)
    out = tmp_path / "runs"
    done = _run_q1(copy, out)
    assert done.returncode == 2, done.stderr
    assert done.stdout == ""
    assert done.stderr.strip().splitlines() == [
        f"error: {manifest}: edited after the dataset was generated: its dataset_hash "
        f"{recorded[:12]} no longer matches its content, and runs record that hash to identify "
        "the dataset; restore the file or generate the dataset again"
    ]
    assert not out.exists()


def _earlier_bpb(manifest: dict[str, Any]) -> None:
    """As a bpb from before the top-level ``physics`` field wrote it: the hash covers only the
    fields that bpb wrote (SHA-256 of the canonical JSON with ``dataset_hash`` empty)."""
    del manifest["physics"]
    body = json.dumps({**manifest, "dataset_hash": ""}, indent=2, sort_keys=True) + "\n"
    manifest["dataset_hash"] = hashlib.sha256(body.encode()).hexdigest()


@pytest.mark.parametrize(
    "change",
    [_earlier_bpb, lambda m: m.pop("dataset_hash")],
    ids=["written by an earlier bpb", "without a hash"],
)
def test_a_manifest_of_an_earlier_bpb_or_without_a_hash_still_runs(
    copy: Path, tmp_path: Path, change: Callable[[dict[str, Any]], object]
) -> None:
    edit(change)(copy / "dataset.json")
    done = _run_q1(copy, tmp_path / "runs")
    assert done.returncode == 0, done.stderr
    manifest = json.loads((copy / "dataset.json").read_text())
    run = json.loads((tmp_path / "runs" / "baseline_stasis" / "run.json").read_text())
    assert run["dataset_hash"] == manifest.get("dataset_hash", run["dataset_hash"])


def test_verify_accepts_a_manifest_an_earlier_bpb_wrote_and_names_an_edit(copy: Path) -> None:
    # verify() hashed the manifest through the model, which fills in fields added since
    # (physics: {}), so an untouched dataset of an earlier bpb read "dataset_hash does not match".
    edit(_earlier_bpb)(copy / "dataset.json")
    assert load_dataset(copy).verify() == []
    edit(lambda m: m.update(seed=m["seed"] + 1))(copy / "dataset.json")
    assert load_dataset(copy).verify() == [
        "dataset.json: dataset_hash does not match the manifest's content"
    ]
