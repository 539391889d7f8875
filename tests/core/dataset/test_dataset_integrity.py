"""A dataset changed after generation: ``verify()`` names every change, and a run or a report
refuses scene folders that no longer match ``index.csv`` instead of asking about whatever
folders are there."""

from __future__ import annotations

import hashlib
import json
import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from PIL import Image

from bpb_core.dataset import load_dataset
from bpb_core.errors import BadInput
from bpb_core.results import load_results
from support.paths import tree

BPB = str(Path(sys.executable).with_name("bpb"))


@pytest.fixture
def copy(small_dataset: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(small_dataset, tmp_path / "ds"))


def drop_index_row(root: Path) -> None:
    lines = (root / "index.csv").read_text().splitlines(keepends=True)
    (root / "index.csv").write_text(
        "".join(line for line in lines if not line.startswith("h1_0001"))
    )


def edit_seed(root: Path) -> None:
    manifest = json.loads((root / "dataset.json").read_text())
    manifest["seed"] += 1
    (root / "dataset.json").write_text(json.dumps(manifest, indent=2, sort_keys=True) + "\n")


def rewrite_truth_and_its_checksum(root: Path) -> None:
    final = root / "h1" / "scene_0000" / "final.json"
    final.write_text(final.read_text().replace('"answer": "T"', '"answer": "F"', 1) + " ")
    digest = hashlib.sha256(final.read_bytes()).hexdigest()
    sums = root / "checksums.sha256"
    sums.write_text(
        "".join(
            f"{digest}  h1/scene_0000/final.json\n"
            if line.endswith(" h1/scene_0000/final.json")
            else line + "\n"
            for line in sums.read_text().splitlines()
        )
    )


def add_scene_folder(root: Path) -> None:
    shutil.copytree(root / "h1" / "scene_0000", root / "h1" / "scene_0099")


def remove_scene_folder(root: Path) -> None:
    shutil.rmtree(root / "h1" / "scene_0002")


UNLISTED = "a scene folder index.csv does not list"
CHANGES: list[tuple[Callable[[Path], None], list[str]]] = [
    (drop_index_row, ["index.csv: content differs", f"h1/scene_0001: {UNLISTED}"]),
    (edit_seed, ["dataset.json: dataset_hash does not match"]),
    (rewrite_truth_and_its_checksum, ["checksums.sha256: content differs from the hash in"]),
    (add_scene_folder, [f"h1/scene_0099: {UNLISTED}"]),
    (
        remove_scene_folder,
        ["h1/scene_0002: listed in index.csv but", "h1/scene_0002/init.json: missing"],
    ),
]


@pytest.mark.parametrize(("change", "expected"), CHANGES, ids=[c.__name__ for c, _ in CHANGES])
def test_verify_names_every_change_made_after_generation(
    copy: Path, change: Callable[[Path], None], expected: list[str]
) -> None:
    assert load_dataset(copy).verify() == []
    change(copy)
    problems = load_dataset(copy).verify()
    for text in expected:
        assert any(p.startswith(text) for p in problems), problems


@pytest.mark.parametrize(
    ("change", "named"),
    [
        (remove_scene_folder, "h1/scene_0002: listed in index.csv but missing"),
        (add_scene_folder, f"h1/scene_0099: {UNLISTED}"),
    ],
)
def test_a_run_on_scene_folders_unlike_the_index_exits_2_naming_the_folder(
    copy: Path, tmp_path: Path, change: Callable[[Path], None], named: str
) -> None:
    change(copy)
    out = str(tmp_path / "r")
    done = subprocess.run(
        [BPB, "run", "--data", str(copy), "--adapter", "baseline:stasis", "--out", out],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().count("\n") == 0
    assert f"{copy}/{named}" in done.stderr
    assert not (tmp_path / "r").exists() or not any((tmp_path / "r").rglob("*.json"))


def test_a_report_on_a_dataset_that_lost_a_scene_after_the_run_says_so(
    copy: Path, tmp_path: Path
) -> None:
    out = tmp_path / "runs"
    common = dict(capture_output=True, text=True, timeout=120)
    ran = subprocess.run([BPB, "run", "--data", str(copy), "--adapter", "baseline:stasis",
                          "--out", str(out)], **common)  # type: ignore[call-overload]  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    remove_scene_folder(copy)
    report = subprocess.run([BPB, "report", str(out), "--out",
                             str(tmp_path / "rep")], **common)  # type: ignore[call-overload]  # fmt: skip
    assert report.returncode == 2, report.stdout + report.stderr
    assert "h1/scene_0002: listed in index.csv but missing" in report.stderr


def test_an_index_listing_a_scene_twice_or_not_utf8_is_refused(copy: Path) -> None:
    index = copy / "index.csv"
    lines = index.read_text().splitlines(keepends=True)
    index.write_text("".join([*lines, lines[1]]))
    with pytest.raises(BadInput, match=r"index\.csv: scene h\d_\d{4} is listed twice"):
        load_dataset(copy)
    index.write_bytes(b"scene_id,horizon,index\n\xff\n")
    with pytest.raises(BadInput, match=r"index\.csv: not UTF-8 text"):
        load_dataset(copy)


def _run_h1(data: Path, tmp_path: Path, out: str = "r") -> subprocess.CompletedProcess[str]:
    """``bpb run`` of the stasis baseline on horizon 1 of ``data`` into ``tmp_path/out``."""
    return subprocess.run(
        [BPB, "run", "--data", str(data), "--adapter", "baseline:stasis", "--out",
         str(tmp_path / out), "--horizons", "1"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip


def test_a_run_refuses_a_truncated_input_image_instead_of_sending_it(
    copy: Path, tmp_path: Path
) -> None:
    image = copy / "h1" / "scene_0001" / "init.png"
    image.write_bytes(image.read_bytes()[: image.stat().st_size * 6 // 10])
    done = _run_h1(copy, tmp_path)
    assert done.returncode == 2, done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith(f"error: {image}: not a readable image (OSError: Truncated File Read)")


def truncate_image(root: Path) -> Path:
    image = root / "h1" / "scene_0001" / "init.png"
    image.write_bytes(image.read_bytes()[: image.stat().st_size * 6 // 10])
    return image


@pytest.mark.parametrize(
    "command",
    [
        ["export", "{data}", "--out", "{tmp}/hf"],
        ["prompt", "h1_0001", "--data", "{data}"],
        ["prompt", "{data}/h1/scene_0001", "--input-mode", "image+state"],
    ],
    ids=["export", "prompt-by-id", "prompt-by-folder"],
)
def test_a_truncated_input_image_is_named_not_exported_or_printed(
    copy: Path, tmp_path: Path, command: list[str]
) -> None:
    image = truncate_image(copy)
    args = [arg.format(data=copy, tmp=tmp_path) for arg in command]
    done = subprocess.run([BPB, *args], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.strip().splitlines() == [
        f"error: {image}: not a readable image (OSError: Truncated File Read); the dataset is "
        "damaged: load_dataset(...).verify() lists what changed"
    ]
    assert done.stdout == ""
    assert not (tmp_path / "hf").exists()


def test_a_truncated_input_image_stops_bpb_human_before_it_serves(
    copy: Path, tmp_path: Path
) -> None:
    from bpb_core.registry import make_registry
    from bpb_core.web.human import HumanSession

    image = truncate_image(copy)
    with pytest.raises(BadInput) as caught:
        HumanSession(copy, tmp_path / "run", "ann", make_registry())
    assert str(caught.value).startswith(f"{image}: not a readable image")
    assert not (tmp_path / "run").exists()


def jpeg_named_png(image: Path) -> None:
    from PIL import Image

    with Image.open(image) as png:
        png.convert("RGB").save(image, format="JPEG")


@pytest.mark.parametrize(
    ("change", "why"),
    [
        (lambda image: image.write_bytes(b""), "an empty file"),
        (lambda image: image.write_bytes(b"GIF87a?"), "not an image file Pillow can read"),
        (jpeg_named_png, "a JPEG image, but its name says PNG"),
    ],
    ids=["empty", "not an image", "jpeg"],
)
def test_an_input_image_that_is_empty_or_not_what_its_name_says_is_refused(
    copy: Path, tmp_path: Path, change: Callable[[Path], None], why: str
) -> None:
    image = copy / "h1" / "scene_0001" / "init.png"
    change(image)
    done = _run_h1(copy, tmp_path)
    assert done.returncode == 2, done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert last == (
        f"error: {image}: not a readable image ({why}); the dataset is damaged: "
        "load_dataset(...).verify() lists what changed"
    )


def test_an_index_saved_by_a_spreadsheet_with_a_bom_and_crlf_still_reads(
    copy: Path, tmp_path: Path
) -> None:
    index = copy / "index.csv"
    index.write_bytes(b"\xef\xbb\xbf" + index.read_bytes().replace(b"\n", b"\r\n"))
    assert [p.split(":")[0] for p in load_dataset(copy).verify()] == ["index.csv"]
    for command in (
        ["run", "--data", str(copy), "--adapter", "baseline:stasis", "--out", str(tmp_path / "r"),
         "--horizons", "1", "--tasks", "q1"],
        ["export", str(copy), "--out", str(tmp_path / "hf"), "--tasks", "q1"],
    ):  # fmt: skip
        done = subprocess.run([BPB, *command], capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, (command[0], done.stderr)
    assert len(list((tmp_path / "r").rglob("q1.json"))) == 3


def test_verify_reads_no_file_outside_the_dataset_and_names_bad_checksum_lines(
    copy: Path,
) -> None:
    # A checksums line naming "../secret" made verify() hash a file outside the dataset, and a
    # garbage line was listed as ": missing".
    (copy.parent / "secret").write_text("not the dataset's")
    sums = copy / "checksums.sha256"
    digest = hashlib.sha256(b"not the dataset's").hexdigest()
    lines = sums.read_text().splitlines()
    sums.write_text("\n".join([*lines, f"{digest}  ../secret", "garbage", ""]))
    problems = load_dataset(copy).verify()
    n = len(lines)
    assert problems[-2:] == [
        f"checksums.sha256: line {n + 1}: not '<sha256>  <path inside the dataset>'",
        f"checksums.sha256: line {n + 2}: not '<sha256>  <path inside the dataset>'",
    ]


def edit_label(path: Path) -> None:
    """Change one answer of ``path`` (a valid file still: only its checksum can tell)."""
    text = path.read_text()
    edited = text.replace('"answer": "T"', '"answer": "F"', 1)
    path.write_text(edited if edited != text else text.replace('"answer": "F"', '"answer": "T"', 1))


CHANGED = "changed after the dataset was generated (its hash differs from"


def test_a_report_refuses_ground_truth_edited_after_the_run_instead_of_scoring_on_it(
    copy: Path, tmp_path: Path
) -> None:
    # An edited final.json that still validated was scored as if it were the dataset's truth.
    assert _run_h1(copy, tmp_path).returncode == 0
    final = copy / "h1" / "scene_0000" / "final.json"
    edit_label(final)
    done = subprocess.run(
        [BPB, "report", str(tmp_path / "r")], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 2, done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith(f"error: {final}: {CHANGED}"), done.stderr


def test_a_run_export_and_library_refuse_an_edited_scene_file(copy: Path, tmp_path: Path) -> None:
    scene = copy / "h1" / "scene_0001" / "init.json"
    scene.write_text(scene.read_text() + "\n")
    done = _run_h1(copy, tmp_path)
    assert done.returncode == 2, done.stderr
    assert f"{scene}: {CHANGED}" in " ".join(done.stderr.split()), done.stderr
    assert not list((tmp_path / "r").rglob("scene_0001/*.json")), "the edited scene was not asked"
    export = subprocess.run(
        [BPB, "export", str(copy), "--out", str(tmp_path / "hf"), "--tasks", "q1"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert export.returncode == 2, export.stderr
    assert CHANGED in " ".join(export.stderr.split())
    with pytest.raises(BadInput, match="changed after the dataset was generated"):
        _ = load_dataset(copy)["h1_0001"].state
    image = copy / "h1" / "scene_0002" / "init.png"
    with Image.open(image) as picture:  # a whole, valid PNG with one pixel changed
        edited = picture.copy()
    edited.putpixel((0, 0), (edited.getpixel((0, 0)) + 1) % 256)  # type: ignore[operator]
    edited.save(image)
    with pytest.raises(BadInput, match=f"{image}: changed after"):
        load_dataset(copy)["h1_0002"].image_bytes()


def test_edited_files_are_used_once_checksums_are_removed(copy: Path, tmp_path: Path) -> None:
    # The way out the message names: a hand-edited dataset without checksums.sha256 is read
    # unchecked, like a folder of hand-made scenes.
    edit_label(copy / "h1" / "scene_0000" / "final.json")
    (copy / "checksums.sha256").unlink()
    assert _run_h1(copy, tmp_path).returncode == 0
    done = subprocess.run(
        [BPB, "report", str(tmp_path / "r")], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize(
    ("content", "problem"),
    [
        ("", "Invalid JSON: EOF while parsing a value at line 1 column 0"),
        ("{not json", "Invalid JSON: key must be a string at line 1 column 2"),
        ('{"scene_id": 3}', "scene_id: Input should be a valid string"),
    ],
    ids=["emptied", "not json", "wrong schema"],
)
def test_a_run_on_a_damaged_ground_truth_exits_2_before_any_call(
    copy: Path, tmp_path: Path, content: str, problem: str
) -> None:
    # bpb run sent every call, then only warned "could not score the run" at the end.
    first = _run_h1(copy, tmp_path)
    assert first.returncode == 0, first.stderr
    before = tree(tmp_path / "r")
    final = copy / "h1" / "scene_0001" / "final.json"
    final.write_text(content)
    for out in ("r", "fresh"):  # an earlier run's folder, and a new one
        done = _run_h1(copy, tmp_path, out)
        assert done.returncode == 2, done.stderr
        [line] = done.stderr.strip().splitlines()
        assert line.startswith(f"error: {final}: {problem}")
    assert tree(tmp_path / "r") == before
    assert not (tmp_path / "fresh").exists()


def test_a_long_lived_process_reads_ground_truth_again_once_it_changes(
    copy: Path, tmp_path: Path
) -> None:
    # read_truth's cache kept the first ground truth read for the life of the process, so a
    # notebook or bpb view went on scoring on it after final.json changed (or was refused).
    assert _run_h1(copy, tmp_path).returncode == 0

    def truths() -> list[object]:
        units = load_results(tmp_path / "r").units
        return units.loc[units["scene_id"] == "h1_0000", "truth"].tolist()

    before = truths()
    assert truths() == before  # a second read (from the cache) is the same
    final = copy / "h1" / "scene_0000" / "final.json"
    edit_label(final)
    with pytest.raises(BadInput, match=f"{final}: {re.escape(CHANGED)}"):
        truths()
    (copy / "checksums.sha256").unlink()  # edited files are then used unchecked
    assert truths() != before
