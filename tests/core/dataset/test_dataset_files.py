"""Generated datasets: layout, byte-identical regeneration, scenes regenerated alone, reader."""

from __future__ import annotations

import csv
import hashlib
import json
from pathlib import Path

import pytest

from bpb_core.dataset import generate_dataset, load_dataset
from bpb_core.dataset.generate import Job, produce, worker_setup
from bpb_core.errors import BadInput
from bpb_core.layout import SceneKey
from bpb_core.registry import Registry
from bpb_tasks.billiards.scene.config import DatasetConfig
from support.dataset_small import SMALL
from support.paths import tree

SCENE_FILES = {"init.json", "final.json", "init.png", "final.png", "trajectory.png"}


def test_layout_index_and_manifest(small_dataset: Path) -> None:
    files = tree(small_dataset)
    for h in ("h1", "h3"):
        for i in range(3):
            assert {f"{h}/scene_{i:04d}/{n}" for n in SCENE_FILES} <= files.keys()
    assert {"dataset.json", "index.csv", "checksums.sha256"} <= files.keys()
    assert {"stats/cue_speed_hist.png", "stats/collisions.png"} <= files.keys()
    rows = list(csv.DictReader((small_dataset / "index.csv").open()))
    assert [r["scene_id"] for r in rows] == [f"h{h}_{i:04d}" for h in (1, 3) for i in range(3)]
    assert {"scene_id", "horizon", "index", "cue_speed", "cue_collision", "stable"} <= rows[
        0
    ].keys()
    manifest = json.loads(files["dataset.json"])
    assert manifest["scenes"] == 6 and manifest["seed"] == SMALL["seed"]
    assert manifest["config"]["physics"]["mu"] == 0.002
    text = files["dataset.json"].decode()
    assert str(small_dataset.parent) not in text  # no absolute paths
    hits = sum(r["cue_collision"] == "true" for r in rows if r["horizon"] == "1")
    assert manifest["summary"]["h1"]["cue_collisions"] == hits


def test_checksums_cover_every_file_and_verify(small_dataset: Path) -> None:
    listed = {
        line.split("  ")[1]
        for line in (small_dataset / "checksums.sha256").read_text().splitlines()
    }
    others = {"dataset.json", "index.csv", "checksums.sha256"}
    assert listed == set(tree(small_dataset)) - others
    assert load_dataset(small_dataset).verify() == []


def test_same_seed_gives_byte_identical_datasets_whatever_the_workers(
    small_dataset: Path, tmp_path: Path
) -> None:
    again = generate_dataset(tmp_path / "again", **SMALL, workers=1)  # type: ignore[arg-type]
    first, second = tree(small_dataset), tree(again)
    assert first.keys() == second.keys()
    assert [k for k in first if first[k] != second[k]] == []


def test_another_seed_gives_another_dataset(small_dataset: Path, tmp_path: Path) -> None:
    other = generate_dataset(tmp_path / "o", 3, [1.0, 3.0], seed=12, workers=1, images=False)
    assert load_dataset(other).dataset_hash != load_dataset(small_dataset).dataset_hash
    assert not (other / "h1" / "scene_0000" / "init.png").exists()


def test_a_scene_regenerated_alone_equals_the_one_in_the_dataset(
    small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    seed = int(SMALL["seed"])  # type: ignore[call-overload]
    setup = worker_setup(registry, "billiards", tmp_path, seed, DatasetConfig(), images=True)
    result = produce(setup, setup.family_cls(), setup.simulator_cls(), Job(3.0, 2))
    for rel, digest in result.files:
        assert hashlib.sha256((small_dataset / rel).read_bytes()).hexdigest() == digest


def test_reader_iterates_filters_and_limits(small_dataset: Path) -> None:
    data = load_dataset(small_dataset)
    assert len(data) == 6 and data.horizons == [1.0, 3.0]
    first = next(iter(data))
    key, scene, final = first.key, first.state, first.truth
    assert key == SceneKey(1.0, 0) and scene.scene_id == final.scene_id == "h1_0000"
    assert final.stability is not None
    assert data["h3_0001"].state.scene_id == "h3_0001" and "h3_0001" in data
    assert data["h3_0001"].image_path("input") == small_dataset / "h3" / "scene_0001" / "init.png"
    picked = load_dataset(small_dataset, horizons=[3], limit=2)
    assert [s.scene_id for s in picked] == ["h3_0000", "h3_0001"]
    with pytest.raises(KeyError, match="h1_0000"):
        picked["h1_0000"]
    assert picked.dataset_hash == data.dataset_hash


def test_an_unknown_scene_id_is_a_key_error_naming_the_folder_and_how_to_list_ids(
    small_dataset: Path,
) -> None:
    # dataset["zzz"] raised a bare KeyError whose message came out in quotes with no way on.
    import bpb_core

    picked = bpb_core.load_dataset(small_dataset, horizons=[3])
    with pytest.raises(KeyError) as caught:
        picked["zzz"]
    assert isinstance(caught.value, BadInput)
    assert str(caught.value) == (
        f"{small_dataset}: no scene 'zzz' in the dataset's selection (ids look like h3_0000); "
        "list them with [scene.scene_id for scene in dataset]"
    )
    assert [scene.scene_id for scene in picked] == ["h3_0000", "h3_0001", "h3_0002"]


def test_reader_rejects_corrupt_files_naming_them(small_dataset: Path, tmp_path: Path) -> None:
    copy = tmp_path / "copy"
    for rel, data in tree(small_dataset).items():
        (copy / rel).parent.mkdir(parents=True, exist_ok=True)
        (copy / rel).write_bytes(data)
    init = copy / "h1" / "scene_0001" / "init.json"
    scene = json.loads(init.read_text())
    scene["balls"][2]["pos"] = [5.0, 0.5]
    init.write_text(json.dumps(scene))
    data = load_dataset(copy)
    with pytest.raises(
        BadInput, match=r"h1/scene_0001/init.json: balls\[2\]\.pos: ball 2 .* off the table"
    ):
        data.scene(SceneKey(1.0, 1))
    assert data.verify() == ["h1/scene_0001/init.json: content differs from its checksum"]
    (copy / "index.csv").write_text("scene_id,horizon,index\nh1_0000,1,zero\n")
    with pytest.raises(BadInput, match=r"index\.csv: line 2: bad horizon or index"):
        load_dataset(copy)
    with pytest.raises(BadInput, match="not a bpb dataset"):
        load_dataset(tmp_path / "nowhere")


def test_refuses_to_write_into_a_non_empty_folder(tmp_path: Path) -> None:
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "notes.txt").write_text("mine")
    with pytest.raises(BadInput, match="busy: --out: exists and is not an empty folder"):
        generate_dataset(tmp_path / "busy", 1, [1.0], 0, workers=1, images=False)
    assert (tmp_path / "busy" / "notes.txt").read_text() == "mine"


def test_stable_only_keeps_stable_scenes_and_counts_the_dropped(tmp_path: Path) -> None:
    out = generate_dataset(tmp_path / "s", 12, [1.0], 3, workers=2, images=False, stable_only=True)
    rows = list(csv.DictReader((out / "index.csv").open()))
    manifest = load_dataset(out).manifest
    assert len(rows) == 12 and all(r["stable"] == "true" for r in rows)
    last = max(int(r["index"]) for r in rows)
    assert manifest.summary["h1"].dropped_unstable == last + 1 - 12
    kept = {int(r["index"]) for r in rows}
    folders = {int(p.name.split("_")[1]) for p in (out / "h1").iterdir()}
    assert folders == kept
