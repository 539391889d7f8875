"""Files a command reads or leaves that are not what bpb wrote: a checksum file that is no
checksum file, an edited ``dataset.json``, the temporary files of a killed write, an
``--api-base`` no call can be sent to. Each is refused in one line naming it (exit 2) before
anything is sent, or cleaned up by the next run."""

from __future__ import annotations

import functools
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from support.fake_openai import fake_server
from support.inprocess import bpb

RUN = ["--adapter", "baseline:stasis", "--tasks", "q1"]

KILLED_WRITE = (  # killed between the temporary file and its rename, as by kill -9
    "import os, pathlib, signal, sys\n"
    "from bpb_core.run_folder import write_bytes_atomic\n"
    "os.replace = lambda *args: os.kill(os.getpid(), signal.SIGKILL)\n"
    "write_bytes_atomic(pathlib.Path(sys.argv[1]), b'{}')\n"
)


@pytest.fixture
def copy(small_dataset: Path, tmp_path: Path) -> Path:
    """A copy of a generated dataset (its checksums and manifest) this test may damage."""
    return Path(shutil.copytree(small_dataset, tmp_path / "data"))


def test_a_checksum_file_that_is_no_checksum_file_is_refused_not_skipped(
    copy: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """A damaged ``checksums.sha256`` turned the integrity check off: an edited ``final.json``
    (every score against it wrong) was run and scored with no word said."""
    truth = copy / "h1" / "scene_0000" / "final.json"
    truth.write_text(truth.read_text().replace('"T"', '"F"'))
    sums = copy / "checksums.sha256"
    sums.write_text("checked by hand\n" + sums.read_text())
    done = bpb(capfd, "run", "--data", str(copy), *RUN, "--out", str(tmp_path / "runs"))
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"error: {sums}: line 1: not '<sha256>  <path inside the dataset>', so the scene files "
        "cannot be checked against it; regenerate the dataset, or remove checksums.sha256 to "
        "use its files unchecked"
    ]
    assert not (tmp_path / "runs").exists()


def test_export_refuses_an_edited_dataset_json_as_run_does(
    copy: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """``bpb export`` published a dataset whose ``dataset.json`` was edited after generation,
    under the dataset_hash of the unedited one, which ``bpb run`` refuses."""
    manifest = copy / "dataset.json"
    fields = json.loads(manifest.read_text())
    manifest.write_text(json.dumps({**fields, "seed": fields["seed"] + 1}, indent=2))
    cli = functools.partial(bpb, capfd)
    run = cli("run", "--data", str(copy), *RUN, "--out", str(tmp_path / "runs"))
    export = cli("export", str(copy), "--out", str(tmp_path / "export"))
    assert (run.returncode, export.returncode) == (2, 2), export.stderr
    [line] = export.stderr.strip().splitlines()
    assert line == run.stderr.strip() and line.startswith(
        f"error: {manifest}: edited after the dataset was generated"
    )
    assert not (tmp_path / "export").exists()


def test_the_next_run_removes_the_temporary_files_a_killed_write_left(
    dataset: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """A run killed between writing an answer's temporary file and renaming it left
    ``.q1.json.<pid>.tmp`` in the scene folder for good; each kill added one."""
    out = tmp_path / "runs"
    run = functools.partial(bpb, capfd, "run", "--data", str(dataset), *RUN, "--out", str(out))
    assert run().returncode == 0
    run_dir = out / "baseline_stasis"
    for target in (run_dir / "h1" / "scene_0000" / "q1.json", run_dir / "run.json"):
        killed = subprocess.run([sys.executable, "-c", KILLED_WRITE, str(target)], check=False)
        assert killed.returncode == -9
    left = sorted(run_dir.rglob(".*.tmp"))
    assert [p.name.split(".")[1] for p in left] == ["run", "q1"]
    again = run()
    assert again.returncode == 0, again.stderr
    assert list(run_dir.rglob(".*.tmp")) == []
    assert json.loads((run_dir / "h1" / "scene_0000" / "q1.json").read_text())["status"] == "ok"


@pytest.mark.parametrize(
    ("api_base", "problem"),
    [
        ("127.0.0.1:{port}/v1", "'127.0.0.1:{port}/v1': not an http:// or https:// URL"),
        ("http://127.0.0.1:{port}/v1?key=1", "'http://127.0.0.1:{port}/v1?key=1': holds a query"),
        ("http://me:pw@127.0.0.1:{port}/v1", "holds a user name or password"),
        ("http://127.0.0.1:{port}0000/v1", "'http://127.0.0.1:{port}0000/v1': Port out of range"),
    ],
)
def test_a_malformed_api_base_is_refused_before_any_call(
    api_base: str,
    problem: str,
    dataset: Path,
    tmp_path: Path,
    secret_key: str,
    capfd: pytest.CaptureFixture[str],
) -> None:
    """Each pair was sent (or tried, with retries) to an endpoint no call could reach as meant:
    a user and password in the URL also went into run.json."""
    with fake_server(dataset) as server:
        given = api_base.format(port=server.port)
        done = bpb(
            capfd, "run", "--data", str(dataset), "--adapter", "litellm:openai/fake-model",
            "--api-base", given, "--out", str(tmp_path / "runs"),
        )  # fmt: skip
        sent = server.stats()["total"]
    assert done.returncode == 2, done.stderr
    [line] = done.stderr.strip().splitlines()
    assert line.startswith(f"error: --api-base {problem.format(port=server.port)}")
    assert line.endswith("; expected a URL like http://127.0.0.1:8000/v1")
    assert "pw" not in line and sent == 0 and not (tmp_path / "runs").exists()
