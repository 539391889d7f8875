"""How ``bpb simulate`` reads scene files and keeps each call's own state."""

from __future__ import annotations

import json
import os
import threading
import time
from pathlib import Path

import pytest

from bpb_core import simulate
from bpb_core.errors import BadInput
from bpb_core.simulate import read_scene, simulate_lines
from bpb_tasks.billiards.bench_compare import random_scene
from bpb_tasks.billiards.scene.model import Scene


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_a_named_pipe_is_read_to_its_end_not_to_its_first_short_read(tmp_path: Path) -> None:
    fifo = tmp_path / "scene.json"
    os.mkfifo(fifo)
    text = random_scene(3, 0).model_dump_json().encode()
    first, second = text[:40], text[40:]

    def write() -> None:
        with open(fifo, "wb", buffering=0) as pipe:
            pipe.write(first)
            time.sleep(0.3)  # the reader's first read returns only the first part
            pipe.write(second)

    writer = threading.Thread(target=write)
    writer.start()
    assert read_scene(fifo, Scene) == random_scene(3, 0)
    writer.join()


def test_a_file_past_the_size_cap_is_one_line_naming_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    big = tmp_path / "big.json"
    big.write_bytes(random_scene(3, 0).model_dump_json().encode() + b" " * 2000)
    assert read_scene(big, Scene) == random_scene(3, 0)
    monkeypatch.setattr(simulate, "MAX_SCENE_BYTES", 1000)
    with pytest.raises(BadInput) as info:
        read_scene(big, Scene)
    assert str(info.value) == f"{big}: larger than 0 MB, not a scene file"


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_an_endless_file_is_refused_not_read_for_ever() -> None:
    with pytest.raises(BadInput, match=r"^/dev/zero: larger than 10 MB, not a scene file$"):
        list(simulate_lines(["/dev/zero"], workers=1))


def test_missing_paths_and_empty_folders_are_named(tmp_path: Path) -> None:
    with pytest.raises(BadInput, match=f"^{tmp_path}/nope.json: no such file or directory$"):
        simulate.scene_files([tmp_path / "nope.json"])
    (tmp_path / "empty").mkdir()
    with pytest.raises(BadInput, match=r"empty: no init\.json and no dataset scene folders"):
        simulate.scene_files([tmp_path / "empty"])


def test_two_calls_consumed_in_turn_keep_their_own_horizon(tmp_path: Path) -> None:
    # simulate_lines kept its job in module globals: two generators consumed alternately (A
    # at horizon 1, B at horizon 4) gave A's later lines B's horizon
    paths = []
    for i in range(600):
        paths.append(tmp_path / f"s{i:03d}.json")
        paths[-1].write_text(random_scene(41, i).model_dump_json())
    a = simulate_lines(paths, horizon=1.0, workers=1)
    b = simulate_lines(paths[:300], horizon=4.0, workers=1)
    got_a, got_b = [], []
    for line_a in a:
        got_a.append(json.loads(line_a)["horizon"])
        line_b = next(b, None)
        if line_b is not None:
            got_b.append(json.loads(line_b)["horizon"])
    assert got_a == [1.0] * 600
    assert got_b == [4.0] * 300
