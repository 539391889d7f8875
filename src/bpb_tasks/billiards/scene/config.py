"""The dataset configuration: every knob of the billiards generator, with its default.

A config file (JSON or TOML, ``bpb generate --config FILE``) holds any subset of
:class:`DatasetConfig`'s fields; missing fields take the defaults below, and the full resolved
config is recorded in the dataset manifest. The default per-horizon cue-speed ranges were
calibrated by :func:`bpb_tasks.billiards.scene.calibrate.calibrate_horizon` so that about half the
scenes at each horizon have a cue-ball collision.
"""

from __future__ import annotations

import json
import math
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import Field, field_validator, model_validator

from bpb_core.errors import BadInput
from bpb_core.validated_files import validate_mapping
from bpb_tasks.billiards.scene.model import MAX_SPEED, Physics, Pockets, StrictModel, Table


class SpeedRange(StrictModel):
    """Cue speeds (m/s) are drawn uniformly from ``[low, high]``."""

    low: float = Field(ge=0)
    high: float = Field(gt=0, le=MAX_SPEED)

    @model_validator(mode="after")
    def _ordered(self) -> SpeedRange:
        if self.low > self.high:
            raise ValueError(f"low {self.low} is above high {self.high}")
        return self


class ImageConfig(StrictModel):
    """Canvas geometry of the rendered PNGs (all three images share it).

    Attributes:
        px_per_m: Pixels per metre of table (600 makes the 2 m x 1 m table 1200 x 600 px).
        margin_left, margin_right, margin_top, margin_bottom: Space around the table for the
            rails, axis ticks and labels, in pixels. Left out of a config, they grow with
            ``px_per_m``, the pockets and a narrow table (:func:`needed_margins`); given, they
            must be at least that (checked before generating).
        compress_level: zlib-ng level of the PNG encoder (0-9; 2, the default, gives smaller
            files than Pillow's level 1, faster; see :mod:`bpb_tasks.billiards.render.png`).
    """

    px_per_m: float = Field(600.0, ge=100, le=3000)
    margin_left: int = Field(116, ge=40)
    margin_right: int = Field(48, ge=20)
    margin_top: int = Field(84, ge=20)
    margin_bottom: int = Field(96, ge=40)
    compress_level: int = Field(2, ge=0, le=9)


MARGINS = ("margin_left", "margin_right", "margin_top", "margin_bottom")


HEADER_SPAN = 820  # px at 600 px per metre from the header's start (60 px left of the table)
# to its end: a title such as "Trajectories, t = 0 to 12.5 s", a gap and the legend


def needed_margins(px_per_m: float, pocket_radius: float, table_width: float) -> dict[str, int]:
    """The smallest margins (px) that hold the header, axes, ticks, labels and the pockets and
    rails beyond the table's edge, as :mod:`~bpb_tasks.billiards.render.canvas` draws them:
    text scales with ``px_per_m / 600``, the axes sit just outside the rails and pockets, and
    the header runs past the table's right edge when the table is narrower than it."""
    s = px_per_m / 600.0
    beyond = max(8, round(0.03 * px_per_m), round(pocket_radius * px_per_m))  # rail or pocket
    axis = beyond + round(6 * s)
    header = (HEADER_SPAN - 60) * s - table_width * px_per_m + 1  # + 1: the table rounded
    return {
        "margin_left": math.ceil(axis + 74 * s),  # the rotated "y (m)" 62 s left of the axis
        "margin_right": math.ceil(max(beyond + 6 * s, header)),  # last tick label, header
        "margin_top": math.ceil(max(46 * s, 2 * beyond - 10 * s)),  # header above the pockets
        "margin_bottom": math.ceil(axis + 54 * s),  # "x (m)" 36 s below the axis
    }


MAX_IMAGE_SIDE = 20_000  # pixels of table per image side
# Pixels of a whole canvas (margins included): drawing one takes about 20 bytes a pixel, so this
# is about 600 MB per worker (the default canvas is 1.1 million, px_per_m 3000 on the
# default table 26.6 million).
MAX_IMAGE_PIXELS = 30_000_000


class CalibrationConfig(StrictModel):
    """How :func:`~bpb_tasks.billiards.scene.calibrate.calibrate_horizon` searches speed ranges.

    Attributes:
        target: Wanted share of scenes with a cue-ball collision.
        samples: Scenes per horizon in the fixed calibration sample.
        low_ratio: The range's lower bound as a fraction of its upper bound.
        seed: Seed of the calibration sample (independent of the dataset seed).
        iterations: Bisection steps on the upper bound.
    """

    target: float = Field(0.5, gt=0, lt=1)
    samples: int = Field(20_000, ge=20, le=200_000)  # about 4 KB each, all held at once
    low_ratio: float = Field(0.2, ge=0, lt=1)
    seed: int = 20260101
    iterations: int = Field(14, ge=4, le=40)


# Calibrated with CalibrationConfig(samples=100_000, iterations=16), otherwise the defaults
# (see docs/dataset-card.md, "Cue-speed calibration").
DEFAULT_SPEED_RANGES: dict[str, SpeedRange] = {
    "1": SpeedRange(low=0.7782, high=3.8908),
    "2": SpeedRange(low=0.3965, high=1.9826),
    "3": SpeedRange(low=0.2678, high=1.3392),
    "4": SpeedRange(low=0.2093, high=1.0463),
    "5": SpeedRange(low=0.1735, high=0.8673),
}


class DatasetConfig(StrictModel):
    """Everything that shapes a generated dataset.

    Attributes:
        family: Scene family plugin that samples the scenes.
        simulator: Simulator plugin that computes the ground truth: its name, or its name and
            the options it is built with, as ``bpb bench sim`` takes contestants
            (``pymunk:dt=0.0005``); recorded with the rest of the config in the manifest.
        table, physics, pockets: The scene's world (defaults of SPEC section 2).
        balls: Number of balls, ids ``0..balls-1``; ball 0 is the cue ball.
        min_gap: Smallest gap (m) between two balls and between a ball and a wall at t = 0.
        pocket_margin: Extra distance (m) beyond the pocket radius that starting centres keep.
        decimals: Positions and velocities in ``init.json`` are rounded to this many decimals.
        speed_ranges: Cue-speed range per horizon, keyed by the horizon in seconds (``"3"``).
        image: Canvas of the rendered PNGs.
        stability_delta: Perturbation size of the stability annotation (m, and a share of the
            cue speed).
        stability_samples: Random perturbations per scene of the stability annotation.
        calibration: Settings of the speed-range calibration.
    """

    family: str = "billiards"
    simulator: str = "analytic"
    table: Table = Field(default_factory=Table)
    physics: Physics = Field(default_factory=Physics)
    pockets: Pockets = Field(default_factory=Pockets)
    balls: int = Field(7, ge=1, le=16)
    min_gap: float = Field(0.001, ge=0)
    pocket_margin: float = Field(0.01, ge=0)
    decimals: int = Field(4, ge=3, le=12)
    speed_ranges: dict[str, SpeedRange] = Field(default_factory=lambda: dict(DEFAULT_SPEED_RANGES))
    image: ImageConfig = Field(default_factory=ImageConfig)
    stability_delta: float = Field(1e-4, gt=0)
    stability_samples: int = Field(64, ge=1, le=100_000)
    calibration: CalibrationConfig = Field(default_factory=CalibrationConfig)

    @model_validator(mode="before")
    @classmethod
    def _fitting_margins(cls, data: Any) -> Any:
        # Margins not given grow with px_per_m above 600 and with the pockets, so that the text
        # fits; at the defaults they are ImageConfig's (116, 48, 84, 96).
        if not isinstance(data, Mapping) or not isinstance(data.get("image", {}), Mapping):
            return data
        image, pockets = dict(data.get("image", {})), data.get("pockets", {})
        table = data.get("table", {})
        ppm = image.get("px_per_m", ImageConfig.model_fields["px_per_m"].default)
        radius = pockets.get("radius", 0.06) if isinstance(pockets, Mapping) else 0.06
        width = table.get("width", 2.0) if isinstance(table, Mapping) else 2.0
        if not all(isinstance(v, int | float) and 0 < v < 1e6 for v in (ppm, radius or 1, width)):
            return data  # the field validators say what is wrong
        needed = needed_margins(ppm, radius, width)
        for key in MARGINS:
            default = ImageConfig.model_fields[key].default
            image.setdefault(key, max(round(default * max(1.0, ppm / 600.0)), needed[key]))
        return {**data, "image": image}

    @field_validator("speed_ranges")
    @classmethod
    def _horizon_keys(cls, ranges: dict[str, SpeedRange]) -> dict[str, SpeedRange]:
        # Keys are looked up as horizon_key(horizon): "1.0" or "1e0" would never match "1".
        out: dict[str, SpeedRange] = {}
        for key, value in ranges.items():
            try:
                seconds = float(key)
            except ValueError:
                seconds = math.nan
            if not 0 < seconds < math.inf:
                raise ValueError(f"key {key!r} is not a horizon in seconds (a positive number)")
            if horizon_key(seconds) in out:
                raise ValueError(f"key {key!r} repeats horizon {horizon_key(seconds)}")
            out[horizon_key(seconds)] = value
        return out

    @model_validator(mode="after")
    def _image_fits(self) -> DatasetConfig:
        for side, metres in (("width", self.table.width), ("height", self.table.height)):
            pixels = metres * self.image.px_per_m
            if pixels > MAX_IMAGE_SIDE:
                raise ValueError(
                    f"table.{side}: {metres:g} m at image.px_per_m {self.image.px_per_m:g} makes "
                    f"a {_count(pixels)} px image side (at most {MAX_IMAGE_SIDE:,})"
                )
        im = self.image
        wide = im.margin_left + round(self.table.width * im.px_per_m) + im.margin_right
        high = im.margin_top + round(self.table.height * im.px_per_m) + im.margin_bottom
        if wide * high > MAX_IMAGE_PIXELS:
            raise ValueError(
                f"image: the table at px_per_m {im.px_per_m:g} plus the margins makes a "
                f"{_count(wide)} x {_count(high)} px image (at most {MAX_IMAGE_PIXELS:,} pixels); "
                "lower image.px_per_m, the margins or the table size"
            )
        return self

    def check_margins(self) -> None:
        """Raise :class:`BadInput` if a margin cannot hold what the images draw in it.

        Checked before generating rather than by the model: a dataset made before margins
        were checked still loads.
        """
        im = self.image
        needed = needed_margins(im.px_per_m, self.pockets.radius, self.table.width)
        for key in MARGINS:
            if getattr(im, key) < needed[key]:
                raise BadInput(
                    f"config: image.{key}: {getattr(im, key)} px cuts off the image's labels or "
                    f"pockets at px_per_m {im.px_per_m:g} with pockets of radius "
                    f"{self.pockets.radius:g} m (needs at least {needed[key]}; leave it out "
                    "for a margin that fits)"
                )

    def speed_range(self, horizon: float) -> SpeedRange:
        """The cue-speed range for ``horizon``; raises :class:`BadInput` if none is set."""
        key = horizon_key(horizon)
        found = self.speed_ranges.get(key)
        if found is None:
            known = ", ".join(sorted(self.speed_ranges, key=float)) or "none"
            raise BadInput(
                f"config: speed_ranges: no cue-speed range for horizon {key} s (have {known}); "
                "add one or run `bpb generate --calibrate`"
            )
        return found


def horizon_key(horizon: float) -> str:
    """The ``speed_ranges`` key of a horizon: ``"3"`` for 3.0, ``"2.5"`` for 2.5."""
    return f"{horizon:g}"


def load_config(path: str | Path | None) -> DatasetConfig:
    """Read a JSON or TOML config file (``None`` gives the defaults).

    Raises:
        BadInput: The file is missing, unparsable, or a field is invalid; the message names the
            file and the field.
    """
    if path is None:
        return DatasetConfig()
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark (Notepad) is fine
    except OSError as exc:
        raise BadInput(f"{path}: cannot read config: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise BadInput(
            f"{path}: cannot read config: not UTF-8 text ({exc.reason} at byte {exc.start})"
        ) from None
    toml = path.suffix.lower() == ".toml"
    try:
        data = tomllib.loads(text) if toml else json.loads(text)
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as exc:
        raise BadInput(f"{path}: not valid {'TOML' if toml else 'JSON'}: {exc}") from None
    if not isinstance(data, dict):
        raise BadInput(f"{path}: (top level): expected an object of config fields")
    return validate_mapping(DatasetConfig, data, str(path))


def _count(pixels: float) -> str:
    return f"{pixels:,.0f}" if pixels < 1e12 else f"{pixels:.3g}"
