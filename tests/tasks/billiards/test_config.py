"""Dataset config files: JSON and TOML, defaults, and one-line errors naming file and field."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings, strategies as st

from bpb_core.errors import BadInput
from bpb_core.validated_files import validate_mapping
from bpb_tasks.billiards.scene.config import (
    DEFAULT_SPEED_RANGES,
    DatasetConfig,
    SpeedRange,
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
    bigger = DatasetConfig.model_validate({"image": {"px_per_m": 800}, "pockets": {"radius": 0.08}})
    assert bigger.image.margin_left > 116 and bigger.image.margin_top > 84
    bigger.check_margins()
    narrow = DatasetConfig.model_validate(
        {"image": {"margin_left": 40}}
    )  # an older manifest still loads
    with pytest.raises(BadInput, match=r"image\.margin_left: 40 px cuts off .* at least 116"):
        narrow.check_margins()


def test_a_byte_order_mark_is_read_past(tmp_path: Path) -> None:
    """Windows Notepad starts UTF-8 files with a BOM; json.loads refused it."""
    (tmp_path / "bom.json").write_bytes(b'\xef\xbb\xbf{"balls": 3}')
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbfballs = 3\n")
    assert load_config(tmp_path / "bom.json").balls == load_config(tmp_path / "bom.toml").balls == 3


# Every field of a config that is not a float, and a few that are, by the kind of value it takes.
TYPED_FIELDS = {
    "balls": "int",
    "decimals": "int",
    "stability_samples": "int",
    "image.margin_left": "int",
    "image.compress_level": "int",
    "calibration.samples": "int",
    "calibration.seed": "int",
    "calibration.iterations": "int",
    "family": "str",
    "simulator": "str",
    "physics.mu": "float",
    "table.width": "float",
    "image.px_per_m": "float",
    "speed_ranges.3.low": "float",
    "pockets.centers[0][1]": "float",
}
_TEXT = st.text(max_size=8)
WRONG = {  # what pydantic used to coerce: true to 1, "7" to 7, 7.0 to 7, 1 to "1"
    "int": st.booleans() | _TEXT | st.integers(0, 20).map(float),
    "float": st.booleans() | _TEXT | st.integers(0, 20).map(str),
    "str": st.booleans() | st.integers() | st.floats(allow_nan=False, allow_infinity=False),
}


def _nested(field: str, value: Any) -> dict[str, Any]:
    """``{"a": {"b": value}}`` for ``a.b``; ``pockets.centers[0][1]`` puts value in a pair."""
    if field == "pockets.centers[0][1]":
        return {"pockets": {"centers": [[1.0, value]]}}
    *outer, last = field.split(".")
    data: dict[str, Any] = {last: value}
    for key in reversed(outer):
        data = {key: data}
    return data


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_a_wrong_typed_field_is_refused_naming_it(data: st.DataObject) -> None:
    """No coercion: ``balls = true`` is not 1 ball and ``seed = "1"`` not seed 1."""
    field = data.draw(st.sampled_from(sorted(TYPED_FIELDS)))
    value = data.draw(WRONG[TYPED_FIELDS[field]])
    text = json.dumps(_nested(field, value))
    with pytest.raises(BadInput) as caught:
        validate_mapping(DatasetConfig, json.loads(text), "c.json")
    message = str(caught.value)
    assert message.startswith(f"c.json: {field}: Input should be a valid "), (text, message)
    assert "\n" not in message


def test_a_float_field_still_takes_an_integer(tmp_path: Path) -> None:
    (tmp_path / "c.toml").write_text(
        "[table]\nwidth = 3\n[physics]\ng = 10\n[image]\npx_per_m = 700\n"
        '[pockets]\ncenters = [[0, 0], [3, 1]]\n[speed_ranges."6"]\nlow = 0\nhigh = 1\n'
    )
    cfg = load_config(tmp_path / "c.toml")
    assert (cfg.table.width, cfg.physics.g, cfg.image.px_per_m) == (3.0, 10.0, 700.0)
    assert cfg.pockets.centers == [(0.0, 0.0), (3.0, 1.0)]
    assert cfg.speed_range(6) == SpeedRange(low=0.0, high=1.0)
