"""The generation config of the slider family (recorded in the dataset manifest)."""

from __future__ import annotations

import json
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, model_validator

from bpb_core.errors import BadInput
from bpb_core.validated_files import validate_mapping


class SliderConfig(BaseModel):
    """Every knob of the slider sampler.

    Attributes:
        family: Always ``slider`` (core checks it against the family asked for).
        simulator: Simulator plugin that computes the ground truth.
        length: Track length (m).
        mu_g: Deceleration of a moving puck (m/s^2).
        speed_low, speed_high: Starting speeds are uniform in this range (m/s); the direction
            is a fair coin.
        margin: Starting positions keep this share of the length from either wall.
        decimals: ``x0`` and ``v0`` are rounded to this many decimals in ``init.json``.
        max_horizon: The longest horizon (s) the family generates.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    family: str = "slider"
    simulator: str = "slider-exact"
    length: float = Field(1.0, gt=0)
    mu_g: float = Field(0.5, gt=0)
    speed_low: float = Field(0.1, ge=0)
    speed_high: float = Field(2.0, gt=0)
    margin: float = Field(0.05, ge=0, lt=0.5)
    decimals: int = Field(4, ge=2, le=12)
    max_horizon: float = Field(30.0, gt=0)

    @model_validator(mode="after")
    def _ordered(self) -> SliderConfig:
        if self.speed_low > self.speed_high:
            raise ValueError(f"speed_low {self.speed_low} is above speed_high {self.speed_high}")
        return self


def load_config(source: Any) -> SliderConfig:
    """A config from ``None`` (defaults), a JSON/TOML file, a mapping or a config.

    Raises:
        BadInput: The file cannot be read or a field is invalid (file and field named).
    """
    if isinstance(source, SliderConfig):
        return source
    if source is None:
        return SliderConfig()
    if isinstance(source, Mapping):
        return validate_mapping(SliderConfig, source, "config")
    path = Path(source)
    try:
        text = path.read_text(encoding="utf-8")
        data = tomllib.loads(text) if path.suffix.lower() == ".toml" else json.loads(text)
    except (OSError, ValueError) as exc:
        raise BadInput(f"{path}: cannot read config: {exc}") from None
    if not isinstance(data, dict):
        raise BadInput(f"{path}: (top level): expected an object of config fields")
    return validate_mapping(SliderConfig, data, str(path))
