"""A scene file the system refuses to write part way (a full disk, a file size limit) is an
error naming it, never a silently shortened file."""

from __future__ import annotations

import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest

BPB = str(Path(sys.executable).with_name("bpb"))
POSIX = pytest.mark.skipif(sys.platform == "win32", reason="umask bits and rlimits are POSIX")


def _file_size_limit(size: int = 20_000) -> None:
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails, not kills
    resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))


def _tree(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*") if p.is_file()}


@POSIX
@pytest.mark.parametrize("workers", ["1", "2"])
def test_a_scene_image_the_system_cuts_short_is_one_line_naming_it_and_the_old_dataset_stays(
    tmp_path: Path, workers: str
) -> None:
    """A full disk or a file size limit was "internal error: OSError: [Errno 27] File too
    large" (exit 3), naming no file. It is the user's to fix: one line naming the file and
    what is left where, exit 2; the dataset --overwrite was replacing stays as it was, and
    the unfinished one is kept where Ctrl-C and SIGTERM leave it."""
    out = tmp_path / "ds"
    args = [BPB, "generate", "--out", str(out), "--per-horizon", "2", "--horizons", "1",
            "--workers", workers]  # fmt: skip
    first = subprocess.run([*args, "--no-images"], capture_output=True, text=True, timeout=300)
    assert first.returncode == 0, first.stderr
    before = _tree(out)
    # The first write of an image past the limit is short (20,000 bytes), the next one fails
    done = subprocess.run(
        [*args, "--overwrite"],
        capture_output=True, text=True, timeout=300, preexec_fn=_file_size_limit,
    )  # fmt: skip
    partial = tmp_path / ".ds.partial"
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"error: {partial}/h1/scene_0000/init.png: cannot write: [Errno 27] File too large; "
        f"{out} is as it was, the unfinished dataset is left in {partial} (delete it to free "
        "its space; running the command again starts it afresh)"
    ]
    assert _tree(out) == before
    assert (partial / "h1" / "scene_0000" / "init.json").is_file()


@POSIX
def test_a_stats_figure_the_system_refuses_is_not_blamed_on_the_scene_family(
    tmp_path: Path,
) -> None:
    """A family's write_stats() that the system refused to let write (a 10 kB figure over a
    9,000-byte limit) was reported as the plugin's bug ("raised OSError", exit 3)."""
    done = subprocess.run(
        [BPB, "generate", "--out", str(tmp_path / "ds"), "--per-horizon", "1", "--horizons", "1",
         "--workers", "1", "--no-images"],
        capture_output=True, text=True, timeout=300,
        preexec_fn=lambda: _file_size_limit(9_000),
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        "error: plugin 'billiards' (bpb_tasks.billiards.hooks) from bpb 0.1.0: scene family "
        "'billiards': write_stats(): cannot write: [Errno 27] File too large; the unfinished "
        f"dataset is left in {tmp_path / '.ds.partial'} (delete it to free its space; running "
        "the command again starts it afresh)"
    ]
