"""A scene that fails stops generation: the scenes before it are written whole and listed, and
its error is the one raised, with the worker's traceback behind it."""

from __future__ import annotations

import hashlib
import traceback
from pathlib import Path

import pytest

import support.flawed_family
from bpb_core.dataset import generate_dataset
from bpb_core.errors import PluginBug
from bpb_core.registry import PluginSource, make_registry


@pytest.mark.parametrize("workers", [1, 2])
def test_a_scene_failing_mid_run_leaves_the_scenes_before_it_listed_and_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, workers: int
) -> None:
    monkeypatch.setenv("BPB_TEST_FLAW", "late_raise")  # make_scene raises from index 5 on
    source = PluginSource("flawed", "bpb-flawed", "1.2", "flawed_family")
    registry = make_registry([(support.flawed_family, source)])
    with pytest.raises(PluginBug, match=r"make_scene\('h1_0005'\) raised RuntimeError") as caught:
        generate_dataset(tmp_path / "data", 12, (1.0,), 0, family="flawed", workers=workers,
                         images=False, registry=registry)  # fmt: skip
    said = "".join(traceback.format_exception(caught.value))
    assert "make_scene exploded" in said and "flawed_family.py" in said  # what BPB_DEBUG shows
    partial = tmp_path / ".data.partial"
    rows = (partial / "index.csv").read_text().splitlines()[1:]
    listed = [row.split(",")[0] for row in rows]
    assert listed == [f"h1_{i:04d}" for i in range(5)]
    sums = [line.split("  ") for line in (partial / "checksums.sha256").read_text().splitlines()]
    assert {rel.split("/")[1] for _, rel in sums} == {f"scene_{i:04d}" for i in range(5)}
    assert len(sums) == 5 * 2  # init.json and final.json of each
    for digest, rel in sums:
        assert hashlib.sha256((partial / rel).read_bytes()).hexdigest() == digest
