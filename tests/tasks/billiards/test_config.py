"""Dataset config files: JSON and TOML, defaults, and one-line errors naming file and field."""

from __future__ import annotations

from pathlib import Path

import pytest

from bpb_core.errors import BadInput
from bpb_tasks.billiards.config import (
    DEFAULT_SPEED_RANGES,
    DatasetConfig,
    config_from_mapping,
    load_config,
)


def test_no_file_gives_the_spec_defaults() -> None:
    cfg = load_config(None)
    assert (cfg.table.width, cfg.table.height) == (2.0, 1.0)
    assert (cfg.physics.mu, cfg.physics.g, cfg.physics.ball_radius) == (0.002, 9.8, 0.028575)
    assert cfg.pockets.radius == 0.06 and len(cfg.pockets.centers) == 6
    assert cfg.balls == 7 and cfg.min_gap == 0.001 and cfg.stability_delta == 1e-4
    assert cfg.speed_ranges == DEFAULT_SPEED_RANGES


def test_json_and_toml_files_override_fields(tmp_path: Path) -> None:
    (tmp_path / "c.json").write_text('{"balls": 5, "physics": {"mu": 0.01}}')
    (tmp_path / "c.toml").write_text(
        'balls = 5\n[physics]\nmu = 0.01\n[speed_ranges."6"]\nlow = 0.1\nhigh = 0.4\n'
    )
    from_json = load_config(tmp_path / "c.json")
    from_toml = load_config(tmp_path / "c.toml")
    assert from_json.balls == from_toml.balls == 5
    assert from_json.physics.mu == from_toml.physics.mu == 0.01
    assert from_json.physics.g == 9.8
    assert from_toml.speed_range(6).high == 0.4


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ('{"balls": 0}', "balls"),
        ('{"physics": {"mu": -1}}', "physics.mu"),
        ('{"speed_ranges": {"3": {"low": 2, "high": 1}}}', "speed_ranges.3"),
        ('{"colour": "red"}', "colour"),
        ('{"image": {"px_per_m": "big"}}', "image.px_per_m"),
    ],
)
def test_bad_field_names_the_file_and_the_field(tmp_path: Path, text: str, field: str) -> None:
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(BadInput) as caught:
        load_config(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: {field}:")
    assert "\n" not in message


def test_unparsable_and_missing_files(tmp_path: Path) -> None:
    (tmp_path / "broken.json").write_text("{not json")
    with pytest.raises(BadInput, match=r"broken\.json: not valid JSON"):
        load_config(tmp_path / "broken.json")
    with pytest.raises(BadInput, match=r"nope\.toml: cannot read config"):
        load_config(tmp_path / "nope.toml")


def test_a_horizon_without_a_speed_range_says_how_to_fix_it() -> None:
    with pytest.raises(
        BadInput, match=r"speed_ranges: no cue-speed range for horizon 7 s.*--calibrate"
    ):
        DatasetConfig().speed_range(7.0)


def test_speed_range_keys_are_read_as_horizons(tmp_path: Path) -> None:
    """``"2.5"``, ``"1.0"`` and ``"3e0"`` all name a horizon; lookups go by the number."""
    (tmp_path / "c.toml").write_text(
        '[speed_ranges."1.0"]\nlow = 1\nhigh = 2\n[speed_ranges."3e0"]\nlow = 0.5\nhigh = 1\n'
    )
    cfg = load_config(tmp_path / "c.toml")
    assert cfg.speed_range(1.0).high == 2 and cfg.speed_range(3.0).high == 1
    assert list(cfg.speed_ranges) == ["1", "3"]
    assert load_config(None).speed_ranges == DEFAULT_SPEED_RANGES


def test_margins_left_out_fit_the_text_and_given_ones_are_checked_before_generating() -> None:
    assert DatasetConfig().image.margin_left == 116  # the paper's canvas is unchanged
    bigger = config_from_mapping({"image": {"px_per_m": 800}, "pockets": {"radius": 0.08}})
    assert bigger.image.margin_left > 116 and bigger.image.margin_top > 84
    bigger.check_margins()
    narrow = config_from_mapping({"image": {"margin_left": 40}})  # an older manifest still loads
    with pytest.raises(BadInput, match=r"image\.margin_left: 40 px cuts off .* at least 116"):
        narrow.check_margins()


def test_a_byte_order_mark_is_read_past(tmp_path: Path) -> None:
    """Windows Notepad starts UTF-8 files with a BOM; json.loads refused it."""
    (tmp_path / "bom.json").write_bytes(b'\xef\xbb\xbf{"balls": 3}')
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbfballs = 3\n")
    assert load_config(tmp_path / "bom.json").balls == load_config(tmp_path / "bom.toml").balls == 3
