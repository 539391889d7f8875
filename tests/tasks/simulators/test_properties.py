"""Invariants of the analytic simulator on random scenes (hypothesis) and float64 vs mpmath."""

from __future__ import annotations

import itertools
import math

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from bpb_tasks.billiards.bench_compare import random_scene, random_scenes
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.stability.margins import pair_margins
from bpb_tasks.billiards.truth.final import final_state
from bpb_tasks.billiards.truth.outcome import Outcome
from bpb_tasks.simulators.analytic import AnalyticSimulator
from support.phys_helpers import PRESSING_BREAK, R, rack, seg_state, state_at

FLOAT = AnalyticSimulator()


@st.composite
def scenes(draw: st.DrawFn) -> Scene:
    seed = draw(st.integers(0, 10**6))
    balls = draw(st.integers(2, 12))
    top = draw(st.sampled_from([1.2, 3.0, 8.0]))
    base = random_scene(
        seed, 0, balls=balls, speeds=(0.05, top), gap=draw(st.sampled_from([1e-3, 1e-6]))
    )
    mu = draw(st.sampled_from([0.002, 0.02, 0.0]))
    data = base.model_dump()
    data["physics"]["mu"] = mu
    data["horizon"] = draw(st.sampled_from([0.5, 1.0, 3.0, 5.0]))
    return Scene.model_validate(data)


def check_times(outcome: Outcome) -> list[float]:
    return sorted({0.0, outcome.horizon, *(e.t for e in outcome.events)})


def alive_states(outcome: Outcome, t: float) -> dict[int, tuple[float, float, float, float]]:
    states = {b: state_at(outcome, b, t) for b in outcome.segments}
    return {b: s for b, s in states.items() if s is not None}


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenes())
def test_invariants_hold_on_random_scenes(s: Scene) -> None:
    assert_invariants(s)


@st.composite
def racks(draw: st.DrawFn) -> Scene:
    """Rack breaks at random angles and speeds: simultaneous contacts everywhere."""
    angle = draw(st.floats(-0.05, 0.05))
    speed = draw(st.floats(0.3, 6.0))
    cue_y = 0.5 + draw(st.floats(-0.02, 0.02))
    mu = draw(st.sampled_from([0.002, 0.0]))
    return rack((speed * math.cos(angle), speed * math.sin(angle)), cue_y=cue_y, mu=mu)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(racks())
def test_invariants_hold_when_breaking_a_rack_of_touching_balls(s: Scene) -> None:
    assert_invariants(s)


def test_the_overlap_of_a_pressing_contact_is_the_only_one_and_is_measured() -> None:
    """The dataset card's pressing contact (balls 5 and 6 overlap 0.52 mm at t = 2.44 s): the
    invariants hold because the overlap margin reports that depth, and only that pair overlaps."""
    s = rack(PRESSING_BREAK)
    assert_invariants(s)
    overlap = pair_margins(FLOAT.run(s), R)[1]
    assert overlap is not None and 5e-4 < overlap < 5.5e-4


def assert_invariants(s: Scene) -> None:
    out = FLOAT.run(s)
    assert len(out.events) <= 40 * len(s.balls) + 200  # bounded event count
    assert FLOAT.run(s) == out  # identical rerun
    width, height = s.table.width, s.table.height
    overlap = pair_margins(out, R)[1]  # a pressing contact, the one overlap the model allows
    energy = math.inf
    for t in check_times(out):
        states = alive_states(out, t)
        for x, y, _, _ in states.values():  # on the table
            assert R - 1e-9 <= x <= width - R + 1e-9 and R - 1e-9 <= y <= height - R + 1e-9
        for a, b in itertools.combinations(states.values(), 2):  # no overlap unmeasured
            depth = 2 * R - math.dist(a[:2], b[:2])
            assert depth <= 1e-9 or (overlap is not None and depth <= overlap * (1 + 1e-9)), t
        now = sum(vx * vx + vy * vy for _, _, vx, vy in states.values())
        assert now <= energy * (1 + 1e-12) + 1e-15  # kinetic energy never increases
        energy = now


@settings(max_examples=100, deadline=None)
@given(scenes())
def test_momentum_conserved_through_each_ball_collision(s: Scene) -> None:
    out = FLOAT.run(s)
    changes = [e.t for e in out.events]
    for e in out.events:
        if e.kind != "ball" or changes.count(e.t) > 1:
            continue  # simultaneous events share segments; checked by the hard cases
        before = [_velocity_before(out, i, e.t) for i in e.ids]
        after = [state_at(out, i, e.t) for i in e.ids]
        for axis in (0, 1):
            total_before = sum(v[axis] for v in before)
            total_after = sum(a[2 + axis] for a in after if a is not None)
            assert total_after == pytest.approx(total_before, abs=1e-12)


def _velocity_before(out: Outcome, ball: int, t: float) -> tuple[float, float]:
    earlier = [seg for seg in out.segments[ball] if seg.t0 < t]
    state = seg_state(earlier[-1], t)
    return state[2], state[3]


def test_float64_matches_mpmath_on_1000_random_scenes() -> None:
    reference = AnalyticSimulator(precision=50)
    worst = 0.0
    for s in random_scenes(1000, seed=7):
        fast, exact = final_state(s, FLOAT.run(s)), final_state(s, reference.run(s))
        assert fast.q1 == exact.q1 and fast.q2 == exact.q2, s.scene_id
        for p, q in zip(
            FLOAT.run(s).positions.values(), reference.run(s).positions.values(), strict=True
        ):
            assert (p is None) == (q is None), s.scene_id
            if p is not None and q is not None:
                worst = max(worst, math.dist(p, q))
    assert worst < 1e-9
