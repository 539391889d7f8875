"""The billiards sampler: geometry invariants, per-scene seeding, cue-only motion."""

from __future__ import annotations

import math

from hypothesis import given, settings, strategies as st

from bpb_core.registry import make_registry
from bpb_tasks.billiards.family import BilliardsFamily
from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.billiards.scene.sampler import scene_rng

CONFIG = DatasetConfig()
FAMILY = BilliardsFamily()
horizons = st.sampled_from([1.0, 2.0, 3.0, 4.0, 5.0])


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**63), horizon=horizons, index=st.integers(0, 99_999))
def test_sampled_scene_respects_gaps_walls_and_pockets(
    seed: int, horizon: float, index: int
) -> None:
    scene = FAMILY.sample(scene_rng(seed, horizon, index), horizon, index, CONFIG)
    r, gap = CONFIG.physics.ball_radius, CONFIG.min_gap
    assert [b.id for b in scene.balls] == list(range(7))
    for ball in scene.balls:
        x, y = ball.pos
        assert r + gap <= x <= CONFIG.table.width - r - gap
        assert r + gap <= y <= CONFIG.table.height - r - gap
        for centre in CONFIG.pockets.centers:
            assert math.dist(ball.pos, centre) >= CONFIG.pockets.radius + CONFIG.pocket_margin
    for i, a in enumerate(scene.balls):
        for b in scene.balls[i + 1 :]:
            assert math.dist(a.pos, b.pos) >= 2 * r + gap


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**32), horizon=horizons, index=st.integers(0, 9999))
def test_only_the_cue_ball_moves_at_a_speed_in_the_horizon_range(
    seed: int, horizon: float, index: int
) -> None:
    scene = FAMILY.sample(scene_rng(seed, horizon, index), horizon, index, CONFIG)
    assert all(b.vel == (0.0, 0.0) for b in scene.balls[1:])
    speed = math.hypot(*scene.ball(0).vel)
    speeds = CONFIG.speed_range(horizon)
    rounding = 1e-4  # velocity components are rounded to 4 decimals
    assert speeds.low - rounding <= speed <= speeds.high + rounding
    assert scene.scene_id == f"h{horizon:g}_{index:04d}"
    assert scene.horizon == horizon


def test_same_seed_horizon_index_gives_the_same_scene_and_others_differ() -> None:
    first = FAMILY.sample(scene_rng(5, 3.0, 7), 3.0, 7, CONFIG)
    again = FAMILY.sample(scene_rng(5, 3.0, 7), 3.0, 7, CONFIG)
    assert first == again
    others = [
        FAMILY.sample(scene_rng(6, 3.0, 7), 3.0, 7, CONFIG),
        FAMILY.sample(scene_rng(5, 2.0, 7), 3.0, 7, CONFIG),
        FAMILY.sample(scene_rng(5, 3.0, 8), 3.0, 7, CONFIG),
    ]
    assert all(o.balls != first.balls for o in others)


def test_cue_directions_cover_the_circle() -> None:
    angles = []
    for i in range(400):
        vx, vy = FAMILY.sample(scene_rng(1, 2.0, i), 2.0, i, CONFIG).ball(0).vel
        angles.append(math.atan2(vy, vx) % (2 * math.pi))
    quadrants = [
        sum(1 for a in angles if q * math.pi / 2 <= a < (q + 1) * math.pi / 2) for q in range(4)
    ]
    assert all(70 <= n <= 130 for n in quadrants), quadrants


def test_family_is_a_registered_plugin_taking_a_plain_mapping() -> None:
    family = make_registry().scene_family("billiards")
    config = {"balls": 4, "speed_ranges": {"2": {"low": 0.1, "high": 0.2}}}
    scene = family.sample(scene_rng(0, 2.0, 0), 2.0, 0, config)
    assert [b.id for b in scene.balls] == [0, 1, 2, 3]
    assert 0.1 - 1e-4 <= math.hypot(*scene.ball(0).vel) <= 0.2 + 1e-4


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32),
    balls=st.integers(1, 12),
    gap=st.floats(0.0, 0.02),
    margin=st.floats(0.0, 0.05),
)
def test_invariants_hold_for_other_ball_counts_and_gaps(
    seed: int, balls: int, gap: float, margin: float
) -> None:
    cfg = DatasetConfig(balls=balls, min_gap=gap, pocket_margin=margin)
    scene = FAMILY.sample(scene_rng(seed, 2.0, 0), 2.0, 0, cfg)
    r = cfg.physics.ball_radius
    assert len(scene.balls) == balls
    for i, a in enumerate(scene.balls):
        assert min(a.pos[0], a.pos[1], 2.0 - a.pos[0], 1.0 - a.pos[1]) >= r + gap
        assert all(math.dist(a.pos, c) >= 0.06 + margin for c in cfg.pockets.centers)
        assert all(math.dist(a.pos, b.pos) >= 2 * r + gap for b in scene.balls[i + 1 :])
