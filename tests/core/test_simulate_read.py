"""How ``bpb simulate``'s batch path reads scene files: whole, whatever kind of file."""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path

import pytest

from bpb_core import simulate


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
@pytest.mark.parametrize("ahead", [False, True], ids=["stat", "read-ahead"])
def test_a_named_pipe_is_read_to_its_end_not_to_its_first_short_read(
    tmp_path: Path, ahead: bool
) -> None:
    # read ahead, the listing's open lets the writer's open through and reads the pipe itself
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
    time.sleep(0.1)  # the writer waits in its open
    names = simulate._scene_names([str(fifo)], ahead=ahead)
    assert simulate._read_all(names) == [first + second]
    writer.join()


@pytest.mark.parametrize("ahead", [False, True], ids=["stat", "read-ahead"])
def test_regular_files_of_any_size_are_read_whole(tmp_path: Path, ahead: bool) -> None:
    sizes = [0, 1, 65535, 65536, 65537, 131072, 200_000]
    for size in sizes:
        (tmp_path / f"{size}.json").write_bytes(bytes(i % 251 for i in range(size)))
    names = simulate._scene_names([str(tmp_path / f"{size}.json") for size in sizes], ahead=ahead)
    assert len(simulate._AHEAD) == (len(sizes) if ahead else 0)
    texts = simulate._read_all(names)
    assert [t == bytes(i % 251 for i in range(len(t))) for t in texts] == [True] * len(sizes)
    assert [len(t) for t in texts] == sizes and not simulate._AHEAD


def test_read_ahead_stops_at_its_budget_and_the_rest_is_read_later(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(simulate, "AHEAD_MAX", 250)
    names = []
    for i in range(5):
        names.append(str(tmp_path / f"{i}.json"))
        Path(names[-1]).write_bytes(bytes([65 + i]) * 100)
    (tmp_path / "folder").mkdir()
    (tmp_path / "folder" / "init.json").write_bytes(b"F")
    names.append(str(tmp_path / "folder"))
    for listed_min in (simulate.LISTED_MIN, 1):  # the rest stat-ed, or found in the listing
        monkeypatch.setattr(simulate, "LISTED_MIN", listed_min)
        listed = simulate._scene_names(names, ahead=True)
        assert sorted(simulate._AHEAD) == names[:3]  # the third passes the budget
        texts = simulate._read_all(listed)
        assert texts == [bytes([65 + i]) * 100 for i in range(5)] + [b"F"]


def test_many_names_in_one_folder_get_the_kinds_stat_would_give(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # past LISTED_MIN names in a folder, kinds come from its listing: the same outcome as a
    # stat of each, for files, folders, pipes, links and missing or dangling names
    from bpb_core.errors import BadInput

    names = []
    for i in range(simulate.LISTED_MIN + 8):
        (tmp_path / f"s{i}.json").write_text("{}")
        names.append(str(tmp_path / f"s{i}.json"))
    (tmp_path / "folder").mkdir()
    (tmp_path / "folder" / "init.json").write_text("{}")
    (tmp_path / "link.json").symlink_to(tmp_path / "s0.json")
    names += [str(tmp_path / "folder"), str(tmp_path / "link.json"), f"{tmp_path}/final.json"]
    if hasattr(os, "mkfifo"):
        os.mkfifo(tmp_path / "pipe.json")
        names.append(str(tmp_path / "pipe.json"))
    (tmp_path / "final.json").write_text("{}")
    simulate._SPECIAL.clear()
    listed = simulate._scene_names(names)
    special = set(simulate._SPECIAL)
    assert len(simulate._kinds(names)) == len(names) - 1  # all but the link
    monkeypatch.setattr(simulate, "LISTED_MIN", 10**9)
    for ahead in (False, True):  # a stat of each, or a read of each (the pipe has no writer)
        simulate._SPECIAL.clear()
        assert simulate._scene_names(names, ahead=ahead) == listed
        assert special == simulate._SPECIAL
    monkeypatch.undo()
    assert listed[-4:-1] == [
        str(tmp_path / "folder" / "init.json"), str(tmp_path / "link.json"),
        str(tmp_path / "init.json"),
    ]  # fmt: skip
    assert str(tmp_path / "link.json") not in special and names[0] not in special
    assert (str(tmp_path / "pipe.json") in special) == hasattr(os, "mkfifo")
    (tmp_path / "dangling.json").symlink_to(tmp_path / "nowhere.json")
    for bad in ("missing.json", "dangling.json"):
        for ahead in (False, True):
            with pytest.raises(BadInput, match=f"{bad}: no such file or directory"):
                simulate._scene_names([*names, str(tmp_path / bad)], ahead=ahead)
