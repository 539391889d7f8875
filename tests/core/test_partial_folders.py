"""Two commands writing one ``--out`` at once: the second is refused, the first's partial
folder is left alone, and a folder left by an interrupted command is reused."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from bpb_core.layout import partial_path
from support.inprocess import bpb

HOLD = (
    "import sys, pathlib\n"
    "from bpb_core.layout import partial_folder\n"
    "with partial_folder(pathlib.Path(sys.argv[1]), 'bpb generate') as p:\n"
    "    (p / 'theirs.txt').write_text('being written')\n"
    "    print('held', flush=True); sys.stdin.read()\n"
)


@contextmanager
def _held(target: Path) -> Iterator[None]:
    """Another process building ``target`` (holding its partial folder) for the block."""
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(target)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "held\n"
        yield
    finally:
        holder.communicate("")


@pytest.mark.parametrize("command", ["generate", "export"])
def test_a_second_command_on_one_out_is_refused_and_the_first_s_work_kept(
    command: str,
    small_dataset: Path,
    tmp_path: Path,
    capfd: pytest.CaptureFixture[str],
) -> None:
    # Each command emptied the one hidden partial folder on start: a second command on the
    # same --out deleted what the first was writing (and both then wrote into one folder).
    out = tmp_path / "out"
    args = {
        "generate": ["generate", "--out", str(out), "--per-horizon", "1", "--no-images"],
        "export": ["export", str(small_dataset), "--out", str(out)],
    }[command]
    with _held(out):  # a process of its own
        second = bpb(capfd, *args)
        theirs = (partial_path(out) / "theirs.txt").read_text()
    assert second.returncode == 2, second.stderr
    assert second.stderr.strip().splitlines()[-1] == (
        f"error: {out}: --out: another bpb {command} is writing it now "
        f"({partial_path(out)} is in use); wait for it to end, or choose another --out"
    )
    assert theirs == "being written" and not out.exists()
    # the holder is gone (as if interrupted): its leftover folder is emptied and reused
    done = bpb(capfd, *args)
    assert done.returncode == 0, done.stderr
    assert not partial_path(out).exists() and not (out / "theirs.txt").exists()
