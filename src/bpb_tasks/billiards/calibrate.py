"""Cue-speed calibration: per-horizon speed ranges giving about 50% cue-ball collisions.

For each horizon a fixed calibration sample of draws (seeded by ``calibration.seed``, independent
of any dataset seed) is simulated at cue speeds ``high * (low_ratio + u * (1 - low_ratio))``. The
share of scenes in which the cue ball touches another ball grows with ``high``; a bisection on
``high`` finds the value where it meets ``calibration.target``. The result is deterministic, so the
defaults shipped in :mod:`bpb_tasks.billiards.config` can be recomputed and checked.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from bpb_core.interfaces import Simulator
from bpb_tasks.billiards.config import DatasetConfig, SpeedRange, horizon_key
from bpb_tasks.billiards.sampler import Draw, build_scene, draw, scene_rng

MAX_HIGH = 64.0  # m/s; a bracket search beyond this means the target cannot be reached


@dataclass(frozen=True)
class Calibration:
    """The calibrated range of one horizon and the collision rate it gives on the sample."""

    horizon: float
    range: SpeedRange
    rate: float
    samples: int


def collision_rate(
    draws: Sequence[Draw],
    horizon: float,
    speeds: SpeedRange,
    config: DatasetConfig,
    simulator: Simulator,
) -> float:
    """Share of ``draws`` whose cue ball touches another ball by ``horizon`` with cue speeds
    drawn from ``speeds``."""
    hits = 0
    for i, d in enumerate(draws):
        speed = speeds.low + d.u * (speeds.high - speeds.low)
        scene = build_scene(d, horizon, i, config, speed=speed)
        hits += bool(simulator.run(scene).cue_contacts())
    return hits / len(draws)


def calibration_draws(horizon: float, config: DatasetConfig) -> list[Draw]:
    """The fixed calibration sample of ``horizon``."""
    cal = config.calibration
    return [draw(scene_rng(cal.seed, horizon, i), config) for i in range(cal.samples)]


def calibrate_horizon(
    horizon: float,
    config: DatasetConfig,
    simulator: Simulator,
    step: Callable[[], None] | None = None,
) -> Calibration:
    """Bisect the top of the speed range of ``horizon`` until the collision rate hits the target.

    Args:
        horizon: Horizon in seconds.
        config: Physics, table, sampling and calibration settings.
        simulator: Computes the collisions (normally ``analytic``).
        step: Called after each evaluation of the rate (for progress bars).

    Raises:
        ValueError: The target is not reached even at :data:`MAX_HIGH` m/s.
    """
    cal = config.calibration
    draws = calibration_draws(horizon, config)

    def rate(high: float) -> float:
        speeds = SpeedRange(low=high * cal.low_ratio, high=high)
        value = collision_rate(draws, horizon, speeds, config, simulator)
        if step is not None:
            step()
        return value

    lo, hi = 0.0, 0.5
    while rate(hi) < cal.target:
        lo, hi = hi, hi * 2
        if hi > MAX_HIGH:
            raise ValueError(f"horizon {horizon:g} s: collision rate stays below {cal.target}")
    for _ in range(cal.iterations):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if rate(mid) < cal.target else (lo, mid)
    high = round((lo + hi) / 2, 3)
    found = SpeedRange(low=round(high * cal.low_ratio, 3), high=high)
    realised = collision_rate(draws, horizon, found, config, simulator)
    return Calibration(horizon, found, realised, len(draws))


def calibrate_ranges(
    horizons: Sequence[float],
    config: DatasetConfig,
    simulator: Simulator,
    step: Callable[[], None] | None = None,
) -> dict[str, Calibration]:
    """Calibrate every horizon; keys are ``speed_ranges`` keys (``"3"``)."""
    return {horizon_key(h): calibrate_horizon(h, config, simulator, step) for h in horizons}
