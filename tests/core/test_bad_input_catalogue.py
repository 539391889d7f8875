"""The bad-input catalogue of the command line's generic options: every row exits 2 with one
line naming the option or the path at fault, and nothing is started or written."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from support.inprocess import bpb

# (command line, text the one line must hold); {tmp} is a fresh folder, {file} a plain file in
# it, {scene} a valid scene file, {data} the small runner dataset, {most} the most worker
# processes a command takes (4 per core) and {over} one more.
CATALOGUE = [
    ("run --timeout nan", "--timeout': 'nan' is not a finite number"),
    ("run --timeout inf", "--timeout': 'inf' is not a finite number"),
    ("run --timeout 0", "--timeout': 0.0 is not in the range x>0"),
    ("run --rpm nan", "--rpm': 'nan' is not a finite number"),
    ("run --tpm inf", "--tpm': 'inf' is not a finite number"),
    ("run --max-cost nan", "--max-cost': 'nan' is not a finite number"),
    ("run --max-cost -1", "--max-cost': -1.0 is not in the range x>0"),
    ("run --concurrency 0", "--concurrency': 0 is not in the range x>=1"),
    ("run --model-arg temperature=NaN --adapter litellm:openai/fake --data {data} --out {tmp}/o",
     "--model-arg 'temperature=NaN': temperature must be a finite number, got nan"),
    ("run --out {file}", "{file}: --out: not a folder"),
    ("run --out {file}/runs --data {data}", "{file}: --out: not a folder"),
    ("run --out /sys/bpb-unwritable --data {data} --adapter baseline:stasis",
     "/sys/bpb-unwritable/baseline_stasis: --out: cannot create the folder"),
    ("generate --out {file}", "{file}: --out: exists and is not an empty folder"),
    ("generate --out /sys/bpb-unwritable/ds --horizons 1 --per-horizon 1",
     "/sys/bpb-unwritable/ds: --out: cannot create the folder"),
    ("generate --out {tmp}/ds --horizons inf", "--horizons: 'inf' must be a positive"),
    ("generate --out {tmp}/ds --workers -1", "--workers: must be at least 1"),
    ("generate --out {tmp}/ds --workers {over}",
     "--workers: at most {most} (4 per core; more only wait for a core), got {over}"),
    ("generate --out {tmp}/ds --per-horizon 2000000000",
     "--per-horizon: at most 100,000 scenes per horizon, got 2,000,000,000"),
    ("generate --out {tmp}/ds --per-horizon 0", "--per-horizon: must be at least 1, got 0"),
    ("simulate {scene} --horizon inf", "--horizon: must be a positive finite number, got inf"),
    ("simulate {scene} --horizon nan", "--horizon: must be a positive finite number, got nan"),
    ("simulate {scene} --horizon -1", "--horizon: must be a positive finite number, got -1"),
    ("simulate {scene} --workers -1", "--workers: must be 0 (automatic) or more, got -1"),
    ("simulate {scene} --workers {over}", "--workers: at most {most} (4 per core"),
    ("simulate {scene} --simulator pymunk --dt nan", "--dt: must be a positive finite number"),
    ("simulate {scene} --simulator pymunk --dt inf", "--dt: must be a positive finite number"),
    ("prompt h1_0000 --data {tmp}/nowhere", "{tmp}/nowhere: --data: no such dataset folder"),
]  # fmt: skip


@pytest.mark.parametrize(("command", "expected"), CATALOGUE, ids=[c for c, _ in CATALOGUE])
def test_bad_option_is_one_line_exit_2(
    command: str, expected: str, tmp_path: Path, dataset: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "file").write_text("not a folder\n")
    names = {"tmp": str(tmp_path), "file": str(tmp_path / "file"), "data": str(dataset)}
    names["scene"] = str(dataset / "h1" / "scene_0000" / "init.json")
    most = 4 * (os.cpu_count() or 1)
    names.update(most=str(most), over=str(most + 1))
    args = [part.format(**names) for part in command.split()]
    before = sorted(p.name for p in tmp_path.iterdir())
    done = bpb(capfd, *args)
    assert done.returncode == 2, done.stderr
    assert done.stdout == ""  # refused before any work, no table or scene line
    line = done.stderr.strip()
    assert "\n" not in line and expected.format(**names) in line, line
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing started


def test_run_file_numbers_must_be_finite(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    config = tmp_path / "paper.toml"
    config.write_text('[[adapter]]\nspec = "baseline:stasis"\ntimeout = inf\n')
    done = bpb(capfd, "run", "--config", str(config), "--dry-run", "--out", str(tmp_path / "o"))
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0
    assert "timeout: must be a positive finite number, got inf" in done.stderr


@pytest.mark.parametrize(
    "command",
    ["simulate {data}", "run --data {data} --adapter baseline:stasis --out {tmp}/runs"],
)
def test_a_scene_folder_symlink_loop_is_named_not_an_internal_error(
    command: str, tmp_path: Path, dataset: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    import shutil

    data = Path(shutil.copytree(dataset / "h1", tmp_path / "scenes" / "h1"))
    (data / "scene_0007").symlink_to("scene_0007")  # a link to itself: opening it loops
    names = {"tmp": str(tmp_path), "data": str(data.parent)}
    args = [part.format(**names) for part in command.split()]
    done = bpb(capfd, *args)
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip() == (
        f"error: {data / 'scene_0007'}: cannot open: Too many levels of symbolic links"
    )
