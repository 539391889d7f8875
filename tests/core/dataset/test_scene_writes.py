"""Scene files are written as ``Path.write_bytes`` writes them, only cheaper (worker.write_file).

The worker writes five files per scene through bare descriptors; a dataset must not notice:
same bytes, same permissions, an older file replaced, and a write the system refuses part way
(a full disk, a file size limit) an error, never a silently shortened file.
"""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from bpb_core.dataset.worker import write_file

BPB = str(Path(sys.executable).with_name("bpb"))
POSIX = pytest.mark.skipif(sys.platform == "win32", reason="umask bits and rlimits are POSIX")


@POSIX
@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_a_scene_file_gets_the_mode_and_bytes_write_bytes_gives(tmp_path: Path, umask: int) -> None:
    data = bytes(range(256)) * 40 + b"\r\n\n"
    old = os.umask(umask)
    try:
        write_file(str(tmp_path / "fast"), data)
        (tmp_path / "plain").write_bytes(data)
    finally:
        os.umask(old)
    fast, plain = tmp_path / "fast", tmp_path / "plain"
    assert fast.read_bytes() == data
    assert fast.stat().st_mode == plain.stat().st_mode == 0o100666 & ~umask


def test_a_scene_file_replaces_a_longer_one(tmp_path: Path) -> None:
    path = tmp_path / "init.png"
    path.write_bytes(b"x" * 5000)
    write_file(str(path), b"short")
    assert path.read_bytes() == b"short"


def test_a_missing_folder_is_the_oserror_write_bytes_raises(tmp_path: Path) -> None:
    path = tmp_path / "gone" / "init.png"
    with pytest.raises(FileNotFoundError) as fast:
        write_file(str(path), b"x")
    with pytest.raises(FileNotFoundError) as plain:
        path.write_bytes(b"x")
    assert str(fast.value) == str(plain.value)


def _file_size_limit() -> None:
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails, not kills
    resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))


@POSIX
def test_a_scene_image_the_system_cuts_short_stops_generate_with_its_oserror(
    tmp_path: Path,
) -> None:
    # The first write of an image past the limit is short (20,000 bytes), the next one fails
    done = subprocess.run(
        [BPB, "generate", "--out", str(tmp_path / "ds"), "--per-horizon", "1", "--horizons", "1",
         "--workers", "1"],
        capture_output=True, text=True, timeout=300, preexec_fn=_file_size_limit,
    )  # fmt: skip
    assert done.returncode == 3, done.stderr
    assert done.stderr.strip().splitlines()[-1] == (
        "internal error: OSError: [Errno 27] File too large (set BPB_DEBUG=1 for a traceback)"
    )
    assert not (tmp_path / "ds").exists()
