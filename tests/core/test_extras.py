"""Each optional extra in a virtualenv of its own, as a user installs it: without an extra, a
command that needs it is one line naming the extra to install (exit 2), never an internal error;
with only ``bpb[report]`` or only ``bpb[inspect]``, the commands their docs give work.

The venvs are made with uv from its cache (``--offline``), pinned to the versions of the venv
running the tests, so no index is reached and each takes seconds.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow
REPO = Path(__file__).resolve().parents[2]
UV = Path(sys.executable).with_name("uv")


def make_venv(root: Path, extra: str | None) -> Path:
    """A venv at ``root`` with bpb (and ``extra``) only; returns its bin folder."""
    if not UV.exists():
        if os.environ.get("CI") == "true":
            pytest.fail(f"{UV}: uv is installed by the README's test command")
        pytest.skip("uv not installed beside this Python")
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(root)], check=True)
    freeze = subprocess.run(
        [str(UV), "pip", "freeze", "--python", sys.executable],
        capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    pins = [line for line in freeze.splitlines() if not line.startswith(("-e", "bpb"))]
    (root / "pins.txt").write_text("\n".join(pins) + "\n")
    spec = f"{REPO}[{extra}]" if extra else str(REPO)
    installed = subprocess.run(
        [str(UV), "pip", "install", "--offline", "-q", "--python", str(root / "bin" / "python"),
         "-c", str(root / "pins.txt"), "-e", spec],
        capture_output=True, text=True,
    )  # fmt: skip
    if "not found in the cache" in installed.stderr:  # uv's cache is the README install's
        pytest.fail(
            f"uv's cache lacks a package: run the README's test command first\n{installed.stderr}"
        )
    assert installed.returncode == 0, installed.stderr
    return root / "bin"


def bpb(bin_dir: Path, *args: str, cwd: Path, **env: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(bin_dir / "bpb"), *args], cwd=cwd, capture_output=True, text=True, timeout=300,
        env={**os.environ, **env},
    )  # fmt: skip


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("extras")


@pytest.fixture(scope="module")
def base(work: Path) -> Path:
    """The base install's bin folder, with a dataset and a baseline run made by it."""
    bin_dir = make_venv(work / "base", None)
    made = bpb(bin_dir, "generate", "--out", "data", "--per-horizon", "2", "--horizons", "1",
               "--seed", "3", cwd=work)  # fmt: skip
    assert made.returncode == 0, made.stderr
    ran = bpb(bin_dir, "run", "--data", "data", "--out", "runs", cwd=work)
    assert ran.returncode == 0, ran.stderr  # the baselines need no extra
    return bin_dir


@pytest.mark.parametrize(
    ("args", "extra"),
    [
        (("report", "runs", "--out", "report"), "report"),
        (("human", "--data", "data", "--out", "runs/human_a", "--name", "a"), "web"),
        (("view", "runs"), "web"),
        (("export", "data", "--format", "hf", "--out", "data-hf"), "hf"),
        (("run", "--data", "data", "--out", "more", "--adapter", "litellm:gpt-5.5"), "litellm"),
        (("simulate", "data/h1/scene_0000/init.json", "--simulator", "pymunk"), "pymunk"),
    ],
)
def test_a_command_without_its_extra_is_one_line_naming_it(
    base: Path, work: Path, args: tuple[str, ...], extra: str
) -> None:
    done = bpb(base, *args, cwd=work, OPENAI_API_KEY="sk-local-never-sent")
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), done.stderr
    assert f"pip install 'bpb[{extra}]'" in lines[0]
    assert "internal error" not in done.stderr and "Traceback" not in done.stderr


def test_with_only_the_report_extra_the_written_report_works(base: Path, work: Path) -> None:
    bin_dir = make_venv(work / "report-only", "report")
    done = bpb(bin_dir, "report", "runs", "--out", "report", cwd=work)
    assert done.returncode == 0, done.stderr
    assert (work / "report" / "report.html").stat().st_size > 0
    assert list((work / "report" / "charts").glob("*.png"))


def test_with_only_the_inspect_extra_its_documented_commands_work(base: Path, work: Path) -> None:
    bin_dir = make_venv(work / "inspect-only", "inspect")
    evaluated = subprocess.run(
        [str(bin_dir / "inspect"), "eval", "bpb/q1", "--model", "mockllm/model", "-T", "data=data",
         "-T", "limit=1", "--log-dir", "logs"],
        cwd=work, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert evaluated.returncode == 0, evaluated.stderr
    done = bpb(bin_dir, "report", "logs", "--out", "inspect-report", cwd=work)
    assert done.returncode == 0, done.stderr
    assert (work / "inspect-report" / "report.html").stat().st_size > 0
