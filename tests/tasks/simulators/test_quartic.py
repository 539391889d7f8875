"""Two moving balls (the quartic case) against brute-force sampling of their distance."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings, strategies as st

from bpb_tasks.simulators.analytic import AnalyticSimulator
from bpb_tasks.simulators.analytic.engine import FLOAT64
from bpb_tasks.simulators.analytic.roots import NO_ROOT, first_contact, quadratic_splits
from support.phys_helpers import R, scene


def path(x: float, y: float, vx: float, vy: float, a: float, t: np.ndarray) -> np.ndarray:
    speed = math.hypot(vx, vy)
    if speed == 0:
        return np.array([[x, y]] * len(t))
    tau = np.minimum(t, speed / a) if a > 0 else t
    s = speed * tau - a * tau * tau / 2
    return np.stack([x + vx / speed * s, y + vy / speed * s], axis=1)


@settings(max_examples=200, deadline=None)
@given(
    st.floats(2 * R + 1e-3, 0.6),
    st.floats(0, 2 * math.pi),
    st.floats(-0.3, 0.3),
    st.floats(0.05, 1.5),
    st.floats(-1.0, 1.0),
    st.floats(-1.0, 1.0),
    st.sampled_from([0.0, 0.0196, 0.2]),
)
def test_first_contact_of_two_moving_balls_matches_sampling(
    dist: float, theta: float, aim: float, speed1: float, u0: float, w0: float, a: float
) -> None:
    # Ball 1 starts ``dist`` from ball 0 and heads roughly at it while ball 0 moves too. A huge
    # table with no pockets, so only the two balls interact within the horizon.
    p0 = (50.0, 50.0)
    p1 = (50 + dist * math.cos(theta), 50 + dist * math.sin(theta))
    back = theta + math.pi + aim
    u1, w1 = speed1 * math.cos(back), speed1 * math.sin(back)
    s = scene(
        [(*p0, u0, w0), (*p1, u1, w1)],
        width=100.0,
        height=100.0,
        pockets=[],
        mu=a / 9.8,
        horizon=3.0,
    )
    hits = [e.t for e in AnalyticSimulator().run(s).events if e.kind == "ball"]
    t = np.linspace(0.0, 3.0, 100_001)
    gap = np.hypot(*(path(*p0, u0, w0, a, t) - path(*p1, u1, w1, a, t)).T) - 2 * R
    inside = np.nonzero(gap <= 0)[0]
    if np.min(np.abs(gap)) < 1e-6:
        return  # too close to call by sampling
    if inside.size == 0:
        assert hits == []
    else:
        assert hits and abs(hits[0] - t[inside[0]]) <= 4e-5


def test_quadratic_splits_degenerate_cases() -> None:
    assert quadratic_splits(0.0, 0.0, 1.0, 9.0)[2] == 0
    assert quadratic_splits(0.0, 2.0, -4.0, 9.0) == (2.0, 0.0, 1)
    assert quadratic_splits(1.0, -3.0, 2.0, 9.0) == (1.0, 2.0, 2)
    assert quadratic_splits(1.0, -3.0, 2.0, 1.5) == (1.0, 0.0, 1)
    assert quadratic_splits(1.0, 0.0, 1.0, 9.0)[2] == 0


def test_first_contact_rules() -> None:
    tol, steps = FLOAT64.time_tol, FLOAT64.max_iter
    # g(t) = (t - 1)^2 - 0.25: falls through zero at t = 0.5 (approach), rises at 1.5.
    assert first_contact((0.0, 0.0, 1.0, -2.0, 0.75), 3.0, tol, steps) == 0.5
    # touching and approaching at 0 -> contact at 0; touching and receding -> none
    assert first_contact((0.0, 0.0, 1.0, -1.0, 0.0), 3.0, tol, steps) == 0.0
    assert first_contact((0.0, 0.0, 1.0, 1.0, 0.0), 3.0, tol, steps) == NO_ROOT
    # tangency (double root at t = 1) is not a contact
    assert first_contact((0.0, 0.0, 1.0, -2.0, 1.0), 3.0, tol, steps) == NO_ROOT
    # contact beyond the interval is not reported
    assert first_contact((0.0, 0.0, 1.0, -2.0, 0.75), 0.4, tol, steps) == NO_ROOT
