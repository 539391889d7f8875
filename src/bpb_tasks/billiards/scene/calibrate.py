"""Cue-speed calibration: per-horizon speed ranges giving about 50% cue-ball collisions.

For each horizon a fixed calibration sample of draws (seeded by ``calibration.seed``, independent
of any dataset seed) is simulated at cue speeds ``high * (low_ratio + u * (1 - low_ratio))``. The
share of scenes in which the cue ball touches another ball grows with ``high``; a bisection on
``high`` finds the value where it meets ``calibration.target``. The result is deterministic, so the
defaults shipped in :mod:`bpb_tasks.billiards.scene.config` can be recomputed and checked.

With the compiled kernel (the analytic simulator on float64 with numba) each evaluation is one
batch call on arrays built straight from the draws, rounded exactly as :func:`build_scene` rounds
them; otherwise every scene is built and simulated one by one.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from bpb_core.errors import BadInput
from bpb_core.interfaces import Simulator
from bpb_tasks.billiards.scene.config import DatasetConfig, SpeedRange
from bpb_tasks.billiards.scene.sampler import Draw, build_scene, draw, scene_rng

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
    drawn from ``speeds``.

    Raises:
        SimulationError: ``simulator`` cannot finish a draw (naming it and its cue speed).
    """
    from bpb_tasks.simulators.analytic.engine import AnalyticSimulator, SimulationError

    first = build_scene(draws[0], horizon, 0, config, speed=1.0)
    if isinstance(simulator, AnalyticSimulator) and simulator.takes_kernel(first, len(draws)):
        return _kernel_rate(draws, horizon, speeds, config)
    hits = 0
    for i, d in enumerate(draws):
        speed = speeds.low + d.u * (speeds.high - speeds.low)
        scene = build_scene(d, horizon, i, config, speed=speed)
        try:
            hits += bool(simulator.run(scene).cue_contacts())
        except SimulationError as exc:  # which scene of the sample, at what speed
            said = SimulationError(f"calibration draw {i} (cue at {speed:.3g} m/s): {exc}")
            said.option = exc.option  # generation names where the option is set
            raise said from None
    return hits / len(draws)


def _kernel_rate(
    draws: Sequence[Draw], horizon: float, speeds: SpeedRange, config: DatasetConfig
) -> float:
    """:func:`collision_rate` in one compiled batch (same rounding as :func:`build_scene`)."""
    from bpb_tasks.simulators.analytic.kernel import run_many_arrays, table_params

    places = config.decimals
    pos = np.array([[(round(x, places), round(y, places)) for x, y in d.positions] for d in draws])
    vel = np.zeros_like(pos)
    for k, d in enumerate(draws):
        speed = speeds.low + d.u * (speeds.high - speeds.low)
        vel[k, 0] = (
            round(speed * math.cos(d.angle), places) + 0.0,
            round(speed * math.sin(d.angle), places),
        )
    count, n = pos.shape[0], pos.shape[1]
    prm, pockets = table_params(build_scene(draws[0], horizon, 0, config, speed=1.0))
    _, status, events = run_many_arrays(
        pos.reshape(-1, 2),
        vel.reshape(-1, 2),
        np.arange(count + 1, dtype=np.int64) * n,
        prm,
        pockets,
        np.full(count, float(horizon)),
        100_000,
    )
    if status.any():
        raise BadInput(
            f"config: --calibrate: horizon {horizon:g} s: a calibration scene needs more than "
            f"100,000 events at cue speeds up to {speeds.high:g} m/s; choose a shorter horizon"
        )
    cue = (events[:, 2] == 0) & ((events[:, 3] == 0) | (events[:, 4] == 0))
    return float(len(np.unique(events[cue, 0])) / count)


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
        BadInput: The target is not reached even at :data:`MAX_HIGH` m/s (the horizon is too
            short for it), or a calibration scene exceeds the event budget; starting
            ``config: `` as the config's other refusals do, which generation turns into the
            config's file.
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
    while (reached := rate(hi)) < cal.target:
        if hi * 2 > MAX_HIGH:
            raise BadInput(
                f"config: --calibrate: horizon {horizon:g} s: the cue ball hits another ball in "
                f"only {reached:.1%} of calibration scenes even at {hi:g} m/s, below the "
                f"calibration.target {cal.target:g}; choose a longer horizon or a lower target"
            )
        lo, hi = hi, hi * 2
    for _ in range(cal.iterations):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if rate(mid) < cal.target else (lo, mid)
    high = round((lo + hi) / 2, 4)
    found = SpeedRange(low=round(high * cal.low_ratio, 4), high=high)
    realised = collision_rate(draws, horizon, found, config, simulator)
    return Calibration(horizon, found, realised, len(draws))
