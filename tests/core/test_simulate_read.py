"""How ``bpb simulate``'s batch path reads scene files: whole, whatever kind of file."""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path

import pytest

from bpb_core import simulate


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_a_named_pipe_is_read_to_its_end_not_to_its_first_short_read(tmp_path: Path) -> None:
    fifo = tmp_path / "scene.json"
    os.mkfifo(fifo)
    first, second = b'{"scene_id": "piped", ', b'"horizon": 1.0}'

    def write() -> None:
        with open(fifo, "wb", buffering=0) as pipe:
            pipe.write(first)
            time.sleep(0.3)  # the reader's first read returns only the first part
            pipe.write(second)

    writer = threading.Thread(target=write)
    writer.start()
    names = simulate._scene_names([str(fifo)])
    assert simulate._read_all(names) == [first + second]
    writer.join()


def test_regular_files_of_any_size_are_read_whole(tmp_path: Path) -> None:
    sizes = [0, 1, 65535, 65536, 65537, 200_000]
    for size in sizes:
        (tmp_path / f"{size}.json").write_bytes(bytes(i % 251 for i in range(size)))
    names = simulate._scene_names([str(tmp_path / f"{size}.json") for size in sizes])
    assert [len(t) for t in simulate._read_all(names)] == sizes
