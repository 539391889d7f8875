"""The files of a slider scene: ``init.json`` (:class:`SliderScene`) and ``final.json``
(:class:`SliderTruth`)."""

from __future__ import annotations

import math

from pydantic import BaseModel, ConfigDict, Field, model_validator


class SliderScene(BaseModel):
    """A puck on a track ``[0, length]`` at t = 0.

    Attributes:
        scene_id: ``h2_0003`` (unique within the dataset).
        horizon: Seconds to simulate.
        length: Track length L (m); the walls are at x = 0 and x = L.
        mu_g: Constant deceleration of a moving puck (m/s^2).
        x0: Starting position (m), in ``[0, L]``.
        v0: Starting velocity (m/s); positive means toward x = L.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    scene_id: str
    horizon: float = Field(gt=0, allow_inf_nan=False)
    length: float = Field(gt=0, allow_inf_nan=False)
    mu_g: float = Field(gt=0, allow_inf_nan=False)
    x0: float = Field(allow_inf_nan=False)
    v0: float = Field(allow_inf_nan=False)

    @model_validator(mode="after")
    def _on_track(self) -> SliderScene:
        if not 0.0 <= self.x0 <= self.length:
            raise ValueError(f"x0 {self.x0} is off the track [0, {self.length}]")
        return self


class SliderTruth(BaseModel):
    """What happens by the horizon.

    Attributes:
        simulator: The simulator (or predictor) that produced it.
        x: Position at the horizon (m), rounded to 6 decimals.
        bounces: Wall hits in ``[0, horizon]``.
        hit_times: When each wall hit happened (s), rounded to 6 decimals.
        stable: Whether the bounce count stays the same when the horizon moves by
            :data:`bpb_tiny.physics.STABILITY_DT` either way (``None``: not annotated).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    scene_id: str
    horizon: float
    simulator: str
    x: float
    bounces: int = Field(ge=0)
    hit_times: list[float] = Field(default_factory=list)
    stable: bool | None = None

    @model_validator(mode="after")
    def _consistent(self) -> SliderTruth:
        if len(self.hit_times) != self.bounces or not math.isfinite(self.x):
            raise ValueError("hit_times must list one time per bounce, and x must be finite")
        return self
