"""The paper-size dataset hits the calibration target: 40-60% cue-ball collisions per horizon."""

from __future__ import annotations

from pathlib import Path

import pytest

from bpb_core.dataset import generate_dataset, load_dataset


@pytest.mark.slow
def test_paper_size_dataset_has_about_half_cue_collisions_at_every_horizon(
    tmp_path: Path,
) -> None:
    root = generate_dataset(tmp_path / "paper", 200, [1, 2, 3, 4, 5], 0, workers=2, images=False)
    summary = load_dataset(root).manifest.summary
    assert sorted(summary) == ["h1", "h2", "h3", "h4", "h5"]
    for label, horizon in summary.items():
        assert horizon.scenes == 200
        assert 0.40 <= horizon.collision_rate <= 0.60, (label, horizon.collision_rate)


def test_moderate_sample_is_near_half_at_each_horizon(tmp_path: Path) -> None:
    root = generate_dataset(tmp_path / "m", 60, [1, 3, 5], 21, workers=2, images=False)
    for label, horizon in load_dataset(root).manifest.summary.items():
        assert 0.25 <= horizon.collision_rate <= 0.75, (label, horizon.collision_rate)
