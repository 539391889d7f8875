"""The docs describe the files bpb writes as they are: the keys of an answer file
(docs/running.md) and where the cache folder is (docs/inspect.md, docs/dataset-card.md)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from bpb_core.dataset.reader import cache_root
from bpb_core.layout import SceneKey
from bpb_core.run_folder import AnswerRecord, write_answer
from support.paths import DOCS


def test_running_md_lists_every_key_an_answer_file_holds(tmp_path: Path) -> None:
    # "metadata" (an adapter's reply metadata, such as baseline:vision's perception error) was
    # written to answer files but missing from the documented list.
    page = (DOCS / "running.md").read_text(encoding="utf-8")
    found = re.search(r"^Answer file: (.*?)`cost` is `null`", page, re.S | re.M)
    assert found is not None
    documented = set(re.findall(r'"(\w+)"', found.group(1)))
    key = SceneKey(1.0, 0)
    record = AnswerRecord(
        scene_id=key.scene_id, horizon=1.0, index=0, task="q1", adapter="x:y", status="ok",
        epoch=2, metadata={"centre_error_mm": 0.5, "read": True},
    )  # type: ignore[arg-type]  # fmt: skip
    data = json.loads(write_answer(tmp_path, key, record).read_text())
    assert documented == set(data) | set(data["usage"])


RULE = "`$BPB_CACHE_DIR` when set, else `$XDG_CACHE_HOME/bpb`, else `~/.cache/bpb`"


@pytest.mark.parametrize("page", ["inspect.md", "dataset-card.md"])
def test_the_cache_folder_is_documented_as_it_is_chosen(
    page: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The pages said "default ~/.cache/bpb", though $XDG_CACHE_HOME, when set, moves it.
    text = " ".join((DOCS / page).read_text(encoding="utf-8").split())
    assert RULE in text
    monkeypatch.delenv("BPB_CACHE_DIR", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    assert cache_root() == tmp_path / "home" / ".cache" / "bpb"
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_root() == tmp_path / "xdg" / "bpb"
    monkeypatch.setenv("BPB_CACHE_DIR", str(tmp_path / "mine"))
    assert cache_root() == tmp_path / "mine"
