"""The compiled event kernel against the pure-Python reference engine: same event log, same
labels, final positions within 1e-9 m, on random scenes of every horizon and speed."""

from __future__ import annotations

import math

import pytest

from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.scene.sampler import build_scene, draw, scene_rng
from bpb_tasks.billiards.truth.outcome import Outcome
from bpb_tasks.simulators.analytic import AnalyticSimulator
from bpb_tasks.simulators.analytic.kernel import outcomes_many
from support.phys_helpers import scene

pytest.importorskip("numba")

PYTHON = AnalyticSimulator(engine="python")
KERNEL = AnalyticSimulator(engine="kernel")


def random_scenes(seed: int, count: int) -> list[Scene]:
    """``count`` sampled scenes over horizons 1-5 s and cue speeds 0.2-12 m/s."""
    cfg = DatasetConfig()
    out = []
    for i in range(count):
        horizon = float(1 + i % 5)
        d = draw(scene_rng(seed, horizon, i), cfg)
        out.append(build_scene(d, horizon, i, cfg, speed=0.2 + 11.8 * d.u))
    return out


def assert_same(ref: Outcome, got: Outcome) -> None:
    assert [(e.kind, e.ids, e.wall) for e in got.events] == [
        (e.kind, e.ids, e.wall) for e in ref.events
    ]
    assert got.cue_contacts() == ref.cue_contacts() and got.cue_walls() == ref.cue_walls()
    for ball, pos in ref.positions.items():
        other = got.positions[ball]
        assert (pos is None) == (other is None)
        if pos is not None and other is not None:
            assert math.dist(pos, other) <= 1e-9
    for ref_e, got_e in zip(ref.events, got.events, strict=True):
        assert abs(ref_e.t - got_e.t) <= 1e-12


def test_kernel_matches_the_python_engine_on_random_scenes() -> None:
    for s in random_scenes(11, 300):
        assert_same(PYTHON.run(s), KERNEL.run(s))


@pytest.mark.slow
def test_kernel_matches_the_python_engine_on_many_scenes() -> None:
    scenes = random_scenes(12, 4000)
    batch = outcomes_many(scenes)
    for i, s in enumerate(scenes):
        ref = PYTHON.run(s)
        assert (
            batch[i].cue_contacts() == ref.cue_contacts()
            and batch[i].cue_walls() == ref.cue_walls()
        )
        assert len(batch[i].events) == len(ref.events)
        for ball, pos in ref.positions.items():
            other = batch[i].positions[ball]
            assert (pos is None) == (other is None)
            if pos is not None and other is not None:
                assert math.dist(pos, other) <= 1e-9


def test_kernel_outcome_is_the_reference_outcome() -> None:
    s = scene([(0.4, 0.45, 3.0, 1.1), (1.0, 0.6, 0.0, 0.0), (1.3, 0.3, 0.0, 0.0)], horizon=4)
    assert KERNEL.run(s) == PYTHON.run(s)  # events, segments and positions, bit for bit here


def test_kernel_runs_scenes_of_other_tables_in_turn_on_their_own_tables() -> None:
    """Scenes of other tables, physics or pockets in turn each run on their own, and so does a
    scene whose pocket or ball list was edited in place."""
    balls = [(0.4, 0.45, 3.0, 1.1), (1.0, 0.6, 0.0, 0.0), (1.3, 0.3, 0.0, 0.0)]
    wide = scene(balls, horizon=4)
    narrow = scene(balls, horizon=4, width=1.5, mu=0.004, pocket_radius=0.08)
    assert KERNEL.run(wide).positions != KERNEL.run(narrow).positions
    for s in (wide, narrow, wide, narrow):
        assert_same(PYTHON.run(s), KERNEL.run(s))
    narrow.pockets.centers[:] = [(0.7, 0.56)]  # in the cue ball's way
    assert_same(PYTHON.run(narrow), KERNEL.run(narrow))
    assert KERNEL.run(narrow).positions[0] is None
    before = KERNEL.run(wide)
    wide.balls[0] = wide.balls[0].model_copy(update={"vel": (-3.0, 1.1)})  # the same scene
    assert_same(PYTHON.run(wide), KERNEL.run(wide))
    assert KERNEL.run(wide).positions != before.positions


def test_outcomes_many_matches_single_runs_and_horizons() -> None:
    scenes = random_scenes(13, 40)
    horizons = [0.5 + 0.1 * i for i in range(40)]
    batch = outcomes_many(scenes, horizons)
    for i, s in enumerate(scenes):
        ref = PYTHON.run(s, horizons[i])
        assert (
            batch[i].cue_contacts() == ref.cue_contacts()
            and batch[i].cue_walls() == ref.cue_walls()
        )
        assert batch[i].positions == ref.positions


def test_outcomes_many_of_mixed_ball_counts_matches_single_runs() -> None:
    # one call over scenes of other ball counts (working arrays made anew when the count
    # changes, shared while it does not) and more events than the event table first holds
    from bpb_tasks.billiards.bench_compare import random_scene

    counts = (2, 7, 7, 4, 1, 4)
    scenes = [random_scene(14, i, balls=counts[i % 6], speeds=(3.0, 8.0)) for i in range(36)]
    batch = outcomes_many(scenes)
    events = 0
    for i, s in enumerate(scenes):
        ref = PYTHON.run(s)
        assert (
            batch[i].cue_contacts() == ref.cue_contacts()
            and batch[i].cue_walls() == ref.cue_walls()
        )
        assert len(batch[i].events) == len(ref.events)
        assert batch[i].positions.keys() == ref.positions.keys()
        for ball, pos in ref.positions.items():
            other = batch[i].positions[ball]
            assert (pos is None) == (other is None)
            if pos is not None and other is not None:
                assert math.dist(pos, other) <= 1e-9
        events += len(ref.events)
    assert events > 4 * len(scenes)  # the table grew


def test_outcomes_many_refuses_scenes_on_different_tables() -> None:
    a = scene([(0.5, 0.5, 1.0, 0.0)])
    b = scene([(0.5, 0.5, 1.0, 0.0)], width=3.0)
    with pytest.raises(ValueError, match="share"):
        outcomes_many([a, b])
