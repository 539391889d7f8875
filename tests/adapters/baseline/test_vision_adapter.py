"""``baseline:vision`` answers from the image alone, records its perception error with each
answer, and turns an unreadable image into an answered "unknown" scored wrong, with its reason."""

from __future__ import annotations

from pathlib import Path

from bpb_core.registry import Registry
from bpb_core.report.build import build_report
from bpb_core.results import load_results, summary
from bpb_core.results.tables import metadata_by_horizon
from bpb_core.run_folder import iter_answers
from bpb_core.runner import evaluate
from bpb_core.runner.options import RunOptions

MEASURES = {"centre_error_mm", "centre_error_max_mm", "speed_error_mps", "angle_error_deg"}
CEILING = {"pixel_ceiling_q1_set", "pixel_ceiling_q2"}


def test_vision_reads_generated_images_and_reports_its_perception(
    small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    specs = ["baseline:vision", "baseline:oracle"]
    evaluate(small_dataset, specs, tmp_path, RunOptions(input_mode="image"), registry=registry)
    records = list(iter_answers(tmp_path / "baseline_vision"))
    assert len(records) == 18 and all(r.status == "ok" for _, r in records)
    assert all(set(r.metadata) == MEASURES | CEILING for _, r in records)
    assert all(float(r.metadata["centre_error_mm"]) < 1.2 for _, r in records)
    assert not any(r.metadata for _, r in iter_answers(tmp_path / "baseline_oracle"))
    report = build_report([tmp_path], registry=registry, n_boot=50)
    table = report.tables["metadata"]
    centre = table[table["measure"] == "centre_error_mm"]
    assert set(centre["run"]) == {"baseline_vision"} and set(centre["horizon"]) == {1.0, 3.0}
    assert (centre["scenes"] == 3).all() and (centre["median"] < 1.2).all()
    wide = metadata_by_horizon(table).set_index("measure")
    assert list(wide.columns) == ["run", "statistic", "h1", "h3"]
    assert wide.loc["centre_error_mm", "h1"] == centre["median"].iloc[0]
    # the image's ceiling stays yes/no through the answer files and is shown as a share
    assert all(isinstance(r.metadata[name], bool) for _, r in records for name in CEILING)
    for name in CEILING:
        assert wide.loc[name, "statistic"] == "share"
        for horizon in (1.0, 3.0):
            kept = [r.metadata[name] for _, r in records if r.horizon == horizon]
            assert wide.loc[name, f"h{horizon:g}"] == sum(kept) / len(kept)


def test_an_unreadable_image_is_answered_unknown_and_scored_wrong(
    dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    # the runner's hand-made dataset carries flat-colour PNGs: no axes to find
    options = RunOptions(input_mode="image")
    evaluate(dataset, ["baseline:vision"], tmp_path, options, registry=registry)
    records = list(iter_answers(tmp_path / "baseline_vision"))
    assert records and all(r.status == "parse_error" for _, r in records)
    assert all("no axis" in str(r.metadata["perception_failed"]) for _, r in records)
    results = load_results([tmp_path / "baseline_vision"], registry=registry)
    row = summary(results.units, results.suites).iloc[0]
    assert (row["q1"], row["q2"], row["q3"]) == (0.0, 0.0, 0.0)
    table = build_report([tmp_path], registry=registry, n_boot=20).tables["metadata"]
    assert table.loc[table["measure"] == "perception_failed", "scenes"].sum() == 6


def test_without_an_image_vision_says_so(dataset: Path, tmp_path: Path, registry: Registry) -> None:
    options = RunOptions(input_mode="state", tasks=("q1",))
    evaluate(dataset, ["baseline:vision"], tmp_path, options, registry=registry)
    records = list(iter_answers(tmp_path / "baseline_vision"))
    assert records and all(r.status == "parse_error" for _, r in records)
    assert all("no image" in str(r.metadata["perception_failed"]) for _, r in records)
