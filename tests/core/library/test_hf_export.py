"""``bpb export --format hf``: a Hugging Face dataset that the real ``datasets`` library loads,
the same bytes for the same dataset, and a ``bpb run --data`` on it that scores like the source."""

from __future__ import annotations

import functools
import io
import json
import re
import shutil
from collections.abc import Callable
from pathlib import Path

import datasets
import pytest
from huggingface_hub import DatasetCard
from PIL import Image

from bpb_core import RunOptions, TextPart, build_messages, load_dataset, make_registry, run_eval
from bpb_core.dataset import generate_dataset
from bpb_core.errors import BadInput
from bpb_core.library.hf_export import export_hf
from support.inprocess import Done, bpb

SCORE_COLUMNS = ["task", "scene_id", "unit", "truth", "pred", "correct"]


@pytest.fixture
def run_bpb(site: Path, capfd: pytest.CaptureFixture[str]) -> Callable[..., Done]:
    """``bpb ARGS`` in this process, ``site`` first on ``sys.path`` (conftest's ``run_bpb``
    runs the console script)."""
    return functools.partial(bpb, capfd, site=site)


@pytest.fixture(scope="module")
def export(small_dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("hf") / "export"
    export_hf(small_dataset, out, shard_rows=4)
    return out


def _load(*args: str, cache: Path, **kwargs: str) -> datasets.DatasetDict:
    loaded = datasets.load_dataset(*args, cache_dir=str(cache), **kwargs)
    assert isinstance(loaded, datasets.DatasetDict)
    return loaded


def test_datasets_loads_rows_features_and_images(
    export: Path, small_dataset: Path, tmp_path: Path
) -> None:
    loaded = _load("parquet", data_dir=str(export), cache=tmp_path)
    assert sorted(loaded) == ["h1", "h3"]
    assert {split: loaded[split].num_rows for split in loaded} == {"h1": 9, "h3": 9}
    features = loaded["h3"].features
    assert isinstance(features["image"], datasets.Image)
    assert features["horizon"] == datasets.Value("float64")
    assert features["stable"] == datasets.Value("bool")
    rows = list(loaded["h3"])
    assert [(r["scene_id"], r["task"]) for r in rows[:4]] == [
        ("h3_0000", "q1"),
        ("h3_0000", "q2"),
        ("h3_0000", "q3"),
        ("h3_0001", "q1"),
    ]
    row = rows[3]
    source = load_dataset(small_dataset)["h3_0001"]
    png = source.image_path("input").read_bytes()
    assert row["image"].size == Image.open(io.BytesIO(png)).size
    assert row["image"].tobytes() == Image.open(io.BytesIO(png)).tobytes()
    registry = make_registry()
    assert json.loads(row["target"]) == registry.task("q1").expected(source.truth)
    (message,) = build_messages("q1", source, "image+state")
    text = message.parts[-1]
    assert isinstance(text, TextPart) and row["prompt_image_state"] == text.text
    assert row["stable"] is source.stable
    assert row["truth"] == (source.folder / "final.json").read_text(encoding="utf-8")


def test_the_dataset_card_gives_splits_by_horizon(export: Path, tmp_path: Path) -> None:
    loaded = _load(str(export), cache=tmp_path)
    assert {split: loaded[split].num_rows for split in loaded} == {"h1": 9, "h3": 9}
    card = DatasetCard.load(export / "README.md")
    assert card.data.license == "mit"
    assert card.data.configs[0]["data_files"][1] == {"split": "h3", "path": "data/h3-*"}
    assert card.data.to_dict()["bpb"]["seed"] == 11
    assert "@misc{" in card.text and '"seed": 11' in card.text


def test_same_dataset_same_bytes(small_dataset: Path, export: Path, tmp_path: Path) -> None:
    again = export_hf(small_dataset, tmp_path / "again", shard_rows=4)
    assert len(again.files) == 6  # 9 rows per horizon in shards of 4
    files = sorted(p.relative_to(export) for p in export.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(again.out) for p in again.out.rglob("*") if p.is_file())
    for name in files:
        assert (export / name).read_bytes() == (again.out / name).read_bytes(), name


def test_a_run_on_the_export_scores_like_one_on_the_source(
    small_dataset: Path, export: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("BPB_CACHE_DIR", str(tmp_path / "cache"))
    options = RunOptions(tasks=("q1", "q2", "q3"))
    on_source = run_eval(small_dataset, "baseline:straight", tmp_path / "source", options)
    on_export = run_eval(export, "baseline:straight", tmp_path / "export", options)
    left = on_source.scores[SCORE_COLUMNS].astype(str).reset_index(drop=True)
    right = on_export.scores[SCORE_COLUMNS].astype(str).reset_index(drop=True)
    assert len(left) == 6 * (6 + 4 + 7)
    assert left.equals(right)
    assert 0 < on_export.scores["correct"].mean() < 1
    unpacked = load_dataset(export).root
    assert unpacked.is_relative_to(tmp_path / "cache")
    for scene in load_dataset(small_dataset):
        for name in ("init.json", "final.json", "init.png"):
            copy = scene.key.dir(unpacked) / name
            assert copy.read_bytes() == (scene.folder / name).read_bytes()


def test_cli_export_run_on_it_and_bad_out(
    small_dataset: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    run_bpb: Callable[..., Done],
) -> None:
    monkeypatch.setenv("BPB_CACHE_DIR", str(tmp_path / "cache"))
    out = tmp_path / "hf"
    done = run_bpb("export", str(small_dataset), "--format", "hf", "--out", str(out))
    assert done.returncode == 0, done.stderr
    assert "exported 18 rows (h1: 9, h3: 9) of q1, q2, q3" in done.stdout
    runs = tmp_path / "runs"
    ran = run_bpb("run", "--data", str(out), "--adapter", "baseline:oracle", "--out", str(runs))
    assert ran.returncode == 0, ran.stderr
    oracle = run_eval(out, "baseline:oracle", runs / "baseline_oracle")  # resumes: nothing asked
    assert len(oracle.scores) == 6 * (6 + 4 + 7) and bool(oracle.scores["correct"].all())
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "notes.txt").write_text("mine", encoding="utf-8")
    bad = run_bpb("export", str(small_dataset), "--out", str(tmp_path / "busy"))
    assert bad.returncode == 2
    assert bad.stderr.strip().endswith("not a bpb export; choose a new folder")
    assert (tmp_path / "busy" / "notes.txt").read_text(encoding="utf-8") == "mine"


def test_a_corrupt_shard_is_named(
    export: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("BPB_CACHE_DIR", str(tmp_path / "cache"))
    broken = tmp_path / "broken"
    shutil.copytree(export, broken)
    shard = sorted((broken / "data").glob("h3-*.parquet"))[0]
    shard.write_bytes(b"not parquet")
    with pytest.raises(BadInput, match=rf"^{re.escape(str(shard))}: not a bpb export shard"):
        load_dataset(broken)
    assert not list((tmp_path / "cache" / "hf").iterdir())  # nothing half-made is left


def test_each_scene_image_is_stored_once(small_dataset: Path, tmp_path: Path) -> None:
    done = export_hf(small_dataset, tmp_path / "hf")
    images = sum(scene.image_path().stat().st_size for scene in load_dataset(small_dataset))
    stored = sum((done.out / name).stat().st_size for name in done.files)
    assert stored < 2 * images  # three rows (tasks) per scene would make it 3x and more


@pytest.mark.parametrize(
    ("column", "value", "message"),
    [
        ("horizon", None, "horizon and index must be"),
        ("index", -1, "horizon and index must be"),
        ("image", {"path": "..", "bytes": b"\x89PNG"}, "image.path: '..' is not an image file"),
    ],
)
def test_an_edited_shard_row_is_named_not_an_internal_error(
    export: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    column: str,
    value: object,
    message: str,
) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    monkeypatch.setenv("BPB_CACHE_DIR", str(tmp_path / "cache"))
    edited = Path(shutil.copytree(export, tmp_path / "edited"))
    shard = sorted((edited / "data").glob("h1-*.parquet"))[0]
    table = pq.read_table(shard)
    values = table.column(column).to_pylist()
    values[0] = value
    field = table.schema.field(column)
    table = table.set_column(
        table.schema.get_field_index(column), field, pa.array(values, field.type)
    )
    pq.write_table(table, shard)
    with pytest.raises(BadInput, match=rf"^{re.escape(str(shard))}: row 0: {re.escape(message)}"):
        load_dataset(edited)


def test_a_failed_export_leaves_the_earlier_one_as_it_was(
    small_dataset: Path,
    tmp_path: Path,
    run_bpb: Callable[..., Done],
) -> None:
    out = tmp_path / "hf"
    assert run_bpb("export", str(small_dataset), "--out", str(out)).returncode == 0
    (out / ".gitattributes").write_text("*.parquet filter=lfs\n", encoding="utf-8")  # a hub clone
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    broken = tmp_path / "broken"
    shutil.copytree(small_dataset, broken)
    (broken / "h3" / "scene_0002" / "init.json").unlink()
    bad = run_bpb("export", str(broken), "--out", str(out))
    assert bad.returncode == 2
    missing = broken / "h3" / "scene_0002" / "init.json"
    assert bad.stderr.strip().splitlines() == [
        f"error: {missing}: cannot read: No such file or directory"
    ]
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken", "hf"]  # no .hf.partial
    again = run_bpb("export", str(small_dataset), "--out", str(out), "--shard-rows", "4")
    assert again.returncode == 0, again.stderr
    assert sorted(p.name for p in (out / "data").iterdir()) == [
        f"h{h}-0000{i}-of-00003.parquet" for h in (1, 3) for i in range(3)
    ]  # the earlier single shards are gone
    assert (out / ".gitattributes").read_text(encoding="utf-8") == "*.parquet filter=lfs\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken", "hf"]


@pytest.mark.parametrize(
    ("out", "message"),
    [
        ("afile", "{tmp}/afile: --out: not a folder; choose a new folder"),
        ("afile/sub", "{tmp}/afile: --out: not a folder (a file is in the way of {tmp}/afile/sub)"),
        ("/dev/null", "/dev/null: --out: not a folder; choose a new folder"),
        ("/proc/x", "/proc/x: --out: cannot create the folder: No such file or directory"),
    ],
)
def test_an_out_that_cannot_be_a_folder_is_one_line(
    small_dataset: Path,
    tmp_path: Path,
    run_bpb: Callable[..., Done],
    out: str,
    message: str,
) -> None:
    if out.startswith("/") and not Path(out).parent.is_dir():
        pytest.skip(f"no {Path(out).parent} here")
    (tmp_path / "afile").write_text("mine", encoding="utf-8")
    bad = run_bpb("export", str(small_dataset), "--out", str(tmp_path / out))
    assert bad.returncode == 2, bad.stderr
    assert bad.stderr.strip().splitlines() == ["error: " + message.format(tmp=tmp_path)]
    assert (tmp_path / "afile").read_text(encoding="utf-8") == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]  # no partial folder


def test_a_missing_image_is_named_and_a_dataset_without_images_exports(
    small_dataset: Path,
    tmp_path: Path,
    run_bpb: Callable[..., Done],
) -> None:
    broken = tmp_path / "broken"
    shutil.copytree(small_dataset, broken)
    (broken / "h3" / "scene_0001" / "init.png").unlink()
    bad = run_bpb("export", str(broken), "--out", str(tmp_path / "hf"))
    assert bad.returncode == 2  # it exported h3_0001 with no image, as if made with --no-images
    missing = broken / "h3" / "scene_0001" / "init.png"
    assert bad.stderr.strip().splitlines() == [
        f"error: {missing}: cannot read: No such file or directory"
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken"]
    plain = generate_dataset(
        tmp_path / "plain", per_horizon=2, horizons=[1.0], seed=5, images=False, workers=1
    )
    done = export_hf(plain, tmp_path / "hf-plain")
    rows = _load("parquet", data_dir=str(done.out), cache=tmp_path / "cache")["h1"]
    assert rows.num_rows == 6
    assert set(rows["image"]) == set(rows["prompt_image"]) == {None}
    assert all(rows["prompt_state"])


def _set_cell(shard: Path, column: str, row: int, value: object) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pq.read_table(shard)
    values = table.column(column).to_pylist()
    values[row] = value
    field = table.schema.field(column)
    table = table.set_column(
        table.schema.get_field_index(column), field, pa.array(values, field.type)
    )
    pq.write_table(table, shard)


def test_verify_on_an_export_checks_the_files_it_carries(
    export: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("BPB_CACHE_DIR", str(tmp_path / "cache"))
    assert (export / "bpb" / "checksums.sha256").is_file()
    assert load_dataset(export).verify() == []  # final.png, stats/ are not exported: not missing
    edited = Path(shutil.copytree(export, tmp_path / "edited"))
    shard = sorted((edited / "data").glob("h1-*.parquet"))[0]
    _set_cell(
        shard, "truth", 0, _cell(shard, "truth", 0).replace('"answer": "F"', '"answer": "T"', 1)
    )
    assert load_dataset(edited).verify() == [
        "h1/scene_0000/final.json: content differs from its checksum"
    ]
    (edited / "bpb" / "checksums.sha256").unlink()  # an export made before bpb kept it
    with pytest.raises(BadInput) as caught:
        load_dataset(edited).verify()
    assert str(caught.value) == (
        f"{edited}: this Hugging Face export has no bpb/checksums.sha256 (made by an earlier "
        "bpb), so its scene files cannot be checked: export the dataset again, or verify the "
        "dataset folder it came from"
    )


def _cell(shard: Path, column: str, row: int) -> str:
    import pyarrow.parquet as pq

    value = pq.read_table(shard).column(column).to_pylist()[row]
    assert isinstance(value, str)
    return value


def test_a_dataset_without_its_checksums_is_not_exported(
    small_dataset: Path,
    tmp_path: Path,
    run_bpb: Callable[..., Done],
) -> None:
    broken = Path(shutil.copytree(small_dataset, tmp_path / "broken"))
    (broken / "checksums.sha256").unlink()
    bad = run_bpb("export", str(broken), "--out", str(tmp_path / "hf"))
    assert bad.returncode == 2, bad.stderr
    assert bad.stderr.strip().splitlines() == [
        f"error: {broken}/checksums.sha256: cannot read: No such file or directory; the dataset "
        "is damaged: load_dataset(...).verify() lists what changed"
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken"]


def test_scene_folders_unlike_the_index_are_not_exported(
    small_dataset: Path,
    tmp_path: Path,
    run_bpb: Callable[..., Done],
) -> None:
    broken = Path(shutil.copytree(small_dataset, tmp_path / "broken"))
    index = broken / "index.csv"
    index.write_text(index.read_text().splitlines()[0] + "\n")  # the rows deleted: 0 scenes
    bad = run_bpb("export", str(broken), "--out", str(tmp_path / "hf"))
    assert bad.returncode == 2, bad.stdout + bad.stderr
    assert bad.stderr.strip().splitlines() == [
        f"error: {broken}/h1/scene_0000: a scene folder index.csv does not list (and 5 more): "
        "the dataset no longer matches its index.csv; restore it or generate it again"
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken"]


@pytest.mark.parametrize(
    ("simulator", "said"),
    [
        ("analytic", "`analytic`: Exact event-driven billiards"),
        ("pymunk:dt=0.0005", "`pymunk:dt=0.0005`: Fixed-step Chipmunk2D (pymunk)"),
    ],
)
def test_the_card_names_the_simulator_that_made_the_truth(
    simulator: str,
    said: str,
    tmp_path: Path,
    run_bpb: Callable[..., Done],
) -> None:
    """The card said "exact physics ground truth" whatever made it, a fixed-step pymunk run
    too; it now names the simulator the dataset's config names, with its own summary."""
    config = tmp_path / "cfg.json"
    config.write_text(json.dumps({"simulator": simulator, "stability_samples": 2}))
    data, out = tmp_path / "ds", tmp_path / "hf"
    made = run_bpb("generate", "--out", str(data), "--config", str(config), "--per-horizon", "1",
                   "--horizons", "1", "--workers", "1", "--no-images")  # fmt: skip
    assert made.returncode == 0, made.stderr
    done = run_bpb("export", str(data), "--format", "hf", "--out", str(out))
    assert done.returncode == 0, done.stderr
    card = DatasetCard.load(out / "README.md").text
    assert f"## Ground truth\n\nComputed by the simulator {said}" in card
    assert "exact physics" not in card  # the family's words claim nothing of the simulator
