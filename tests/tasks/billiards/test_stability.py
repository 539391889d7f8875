"""The stability annotation as a measured probability: flip rates under random perturbations,
their upper bound, the Q3 spread, the pocket-edge margin and the reasons reports count."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bpb_tasks.billiards.bench_compare import random_scene
from bpb_tasks.billiards.family import BilliardsFamily
from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.stability.annotation import (
    Tally,
    annotate,
    copy_budget,
    kernel_horizon_gap,
    labels,
    perturbation_arrays,
    tally_copies,
    unvalidated_copy,
    upper_bound,
)
from bpb_tasks.billiards.stability.margins import (
    events_horizon_gap,
    pair_margins,
)
from bpb_tasks.billiards.truth.final import OVERLAP, UNFINISHED, final_state
from bpb_tasks.billiards.truth.outcome import Event, Outcome, Segment
from bpb_tasks.simulators.analytic import AnalyticSimulator
from bpb_tasks.simulators.analytic.engine import SimulationError
from support.phys_helpers import PRESSING_BREAK, R, rack, scene

PYTHON = AnalyticSimulator(engine="python")


def test_upper_bound_is_the_exact_clopper_pearson_bound() -> None:
    assert upper_bound(0, 64) == pytest.approx(1 - 0.05 ** (1 / 64), rel=1e-9)
    assert upper_bound(1, 10) == pytest.approx(0.39416, abs=1e-5)
    assert upper_bound(5, 5) == 1.0


def test_isolated_roll_has_no_flips_and_a_tiny_spread() -> None:
    st = annotate(scene([(0.5, 0.5, 0.3, 0.0), (0.5, 0.2, 0.0, 0.0)], horizon=1), samples=32)
    assert st.stable and st.samples == 32 and st.flip_rate == 0.0
    assert st.flip_rates == {"q1": 0.0, "q2": 0.0, "pocketed": 0.0}
    assert st.flip_rate_upper95 == pytest.approx(1 - 0.05 ** (1 / 32))
    # every centre moves 1e-4 m and the cue speed changes by at most 1e-4 of 0.3 m/s
    assert 5e-5 < st.q3_spread < 2e-4 and st.q3_stable


def test_perturbations_have_the_documented_size() -> None:
    s = scene([(0.5, 0.5, 0.8, 0.6), (1.0, 0.3, 0.0, 0.0), (1.5, 0.7, 0.0, 0.0)])
    ids, pos, vel = perturbation_arrays(s, 1e-4, 50)
    assert ids == [0, 1, 2] and pos.shape == vel.shape == (50, 3, 2)
    moved = [math.dist(p, b.pos) for row in pos.tolist() for p, b in zip(row, s.balls, strict=True)]
    assert max(abs(m - 1e-4) for m in moved) < 1e-12
    kicks = [math.dist(v[0], (0.8, 0.6)) for v in vel.tolist()]
    assert max(abs(k - 1e-4 * 1.0) for k in kicks) < 1e-12
    assert (vel[:, 1:] == 0).all()
    again = perturbation_arrays(s, 1e-4, 50)[1]
    assert (again == pos).all()


def test_grazing_contact_flips_q1_often() -> None:
    s = scene([(0.5, 0.5, 1.0, 0.0), (1.0, 0.5 + 2 * R * (1 - 1e-9), 0.0, 0.0)], horizon=2)
    st = annotate(s)
    assert not st.stable and "q1:1" in st.flips
    assert 0.2 < st.flip_rates["q1"] < 0.8 and st.flip_rate >= st.flip_rates["q1"]
    assert st.flip_rate_upper95 > st.flip_rate


def test_pocket_gap_is_the_nearest_pass_of_a_pocket_not_entered() -> None:
    # rolls along y = 0.5 under pockets at (1, 0.9) (0.4 away) and (1.8, 0.58) (0.08 away)
    s = scene(
        [(0.3, 0.5, 1.5, 0.0)], pockets=[(1.0, 0.9), (1.8, 0.58)], pocket_radius=0.06, horizon=2
    )
    assert annotate(s, samples=4).pocket_gap == pytest.approx(0.08 - 0.06, abs=1e-12)
    # a ball that enters the pocket is not measured against that pocket
    into = scene([(0.3, 0.5, 1.5, 0.0)], pockets=[(1.8, 0.5)], horizon=2)
    assert PYTHON.run(into).positions[0] is None
    assert annotate(into, samples=4).pocket_gap is None


def test_chaotic_final_positions_make_q3_unstable_with_stable_labels() -> None:
    # scene 1 at 3 s, seed 0: several collisions spread final positions by ~5 cm
    made = BilliardsFamily().make_scene(DatasetConfig(), AnalyticSimulator(), 0, 3.0, 1)
    st = made.truth.stability
    assert st is not None and st.flip_rate == 0.0
    assert st.q3_spread > R / 2 and not st.q3_stable and not st.stable
    assert made.truth.unstable_reasons == ["q3"]


def test_kernel_batch_and_python_engine_annotate_alike() -> None:
    """The kernel's array tally equals running every copy through the Python engine."""
    family, cfg = BilliardsFamily(), DatasetConfig()
    scenes = [family.make_scene(cfg, PYTHON, 0, float(1 + i % 5), i).scene for i in range(16)]
    scenes.append(scene([(0.5, 0.5, 1.0, 0.0), (1.0, 0.5 + 2 * R * (1 - 1e-9), 0.0, 0.0)]))
    unstable = 0
    for s in scenes:
        python = annotate(s, simulator=PYTHON, samples=32)
        assert python == annotate(s, simulator=AnalyticSimulator(), samples=32)
        unstable += not python.stable
    assert unstable >= 2  # flips and spreads were compared, not only zeros


def test_scenes_with_more_balls_than_a_kernel_mask_holds_annotate_like_the_python_engine() -> None:
    """The kernel keeps one bit per ball in an int64; a hand-written scene of 70 balls where
    the cue ball hits ball 69 raised OverflowError (a PluginBug from `bpb simulate
    --stability`). Such scenes now take the copy-by-copy path."""
    grid = [(1.0 + 0.06 * i, 0.2 + 0.2 * j, 0.0, 0.0) for i in range(17) for j in range(4)]
    crowd = scene([(0.3, 0.5, 1.0, 0.0), *grid, (0.6, 0.5, 0.0, 0.0)])
    assert len(crowd.balls) == 70 and crowd.balls[-1].id == 69
    kernel = annotate(crowd, simulator=AnalyticSimulator(), samples=16)
    assert kernel == annotate(crowd, simulator=PYTHON, samples=16)
    assert "q1:1" in kernel.flips  # the cue ball runs on into the crowd: flips were compared


def test_compiled_horizon_gap_is_the_reference_to_the_bit() -> None:
    """The kernel reads the horizon gap off its event rows in one call; it must equal the
    reference's gap of a run to the horizon + 1 s exactly, say so when there is no event, and
    stop at the event cap as the engine's capped run does, with the same gap or None."""
    gaps, capped = [], []
    for i in range(60):
        s = random_scene(8, i, balls=2 + i % 9, speeds=(0.05, 3.0))
        expected = events_horizon_gap(PYTHON.run(s, s.horizon + 1.0).events, s.horizon)
        gap = kernel_horizon_gap(s, s.horizon, PYTHON.max_events)
        assert (gap is None) == (expected is None)
        if gap is not None and expected is not None:
            assert gap.hex() == expected.hex()
            gaps.append(gap)
        nominal = len(PYTHON.run(s).events)
        for cap in (nominal // 2, nominal, nominal + 1):
            events, finished = PYTHON.with_max_events(cap).capped_events(s, s.horizon + 1.0)
            reference = events_horizon_gap(events, s.horizon, finished=finished)
            gap = kernel_horizon_gap(s, s.horizon, cap)
            assert (gap is None) == (reference is None)
            if gap is not None and reference is not None:
                assert gap.hex() == reference.hex()
                if not finished:
                    assert reference == expected  # measured at the cap: the uncapped gap
                    capped.append(gap)
    assert len(gaps) > 50 and len(capped) > 20
    still = scene([(0.5, 0.5, 0.0, 0.0), (1.0, 0.5, 0.0, 0.0)])
    assert kernel_horizon_gap(still, 1.0, 100) is None
    bouncing = scene([(0.5, 0.5, 3.0, 0.0)], mu=0.0, horizon=5)
    assert kernel_horizon_gap(bouncing, 5.0, 3) is None  # the cap came before the horizon


def test_the_horizon_gap_run_stops_at_the_event_cap_instead_of_failing_the_scene() -> None:
    """The horizon gap looks 1 s past the horizon, under the simulator's event cap. A scene
    whose run to its horizon fits the cap but whose extra second does not failed its
    annotation ('more than 6 events before t=4.0': `bpb simulate --stability` and generation
    stopped there). The run now stops at the cap. The first event after the horizon came
    before it, so the gap is the uncapped one; when only a stop did, the events do not decide
    it and it is None (not measured); `stable` does not depend on it. Python and kernel paths
    agree."""
    bouncing = scene([(0.5, 0.5, 0.0, 2.0), (1.5, 0.5, 0.0, 0.0)], horizon=3, pockets=[])
    stopping = scene([(0.5, 0.5, 0.0, 1.0), (1.5, 0.5, 0.0, 0.0)], horizon=3, mu=0.032, pockets=[])
    found = []
    for s in (bouncing, stopping):
        base = PYTHON.run(s)
        cap = len(base.events)
        later = PYTHON.run(s, 4.0)
        assert len(later.events) > cap  # the extra second crosses the cap
        python = annotate(s, base, simulator=PYTHON.with_max_events(cap), samples=8)
        kernel = AnalyticSimulator(engine="kernel", max_events=cap)
        assert python == annotate(s, base, simulator=kernel, samples=8)
        assert python.stable and python.flip_rate == 0.0
        found.append(
            (python.horizon_gap, events_horizon_gap(later.events, 3.0), later.events[cap].kind)
        )
    (gap, uncapped, kind), (unmeasured, beyond, stop) = found
    assert kind == "wall" and gap == uncapped and gap == pytest.approx(0.1117, abs=1e-4)
    assert stop == "stop" and unmeasured is None and beyond == pytest.approx(0.883, abs=1e-3)


def kernel_tally(
    s: Scene, base: Outcome, ids: list[int], pos: np.ndarray, vel: np.ndarray, budget: int
) -> Tally:
    """The tally of copies run in the kernel, as :func:`annotate` makes it."""
    from bpb_tasks.billiards.stability.kernel import copy_labels

    copies, finals = copy_labels(s, ids, pos, vel, budget)
    nominal = np.array([base.positions[i] or (np.nan, np.nan) for i in ids])
    return tally_copies(labels(base), copies, finals, nominal)


def test_near_miss_gap_on_named_cases() -> None:
    """Nothing moves (no gap), one ball rolls past another, a graze, a stop short of a ball,
    and a pair that touched (skipped); no overlap in any."""
    cases = [
        scene([(0.5, 0.5, 0.0, 0.0), (1.0, 0.5, 0.0, 0.0)]),
        scene([(0.5, 0.5, 0.6, 0.0), (1.0, 0.6, 0.0, 0.0)]),
        scene([(0.5, 0.5, 0.6, 0.0), (1.0, 0.5 + 2 * R * (1 + 1e-9), 0.0, 0.0)]),
        scene([(0.5, 0.5, 0.1, 0.0), (1.0, 0.5, 0.0, 0.0)]),
        scene([(0.5, 0.5, 1.0, 0.0), (1.0, 0.5, 0.0, 0.0), (1.5, 0.8, 0.0, 0.0)], mu=0.0),
    ]
    gaps = []
    for case in cases:
        gap, overlap = pair_margins(PYTHON.run(case), R)
        assert overlap is None
        gaps.append(gap)
    assert gaps[0] is None
    assert gaps[1] == pytest.approx(0.1 - 2 * R, abs=1e-12)
    graze = gaps[2]
    assert graze is not None and 0 < graze < 1e-9


def test_the_overlap_of_a_pressing_contact_is_measured_and_makes_the_scene_unstable() -> None:
    """The dataset card's pressing contact: after the rack break balls 5 and 6 overlap by
    0.52 mm at t = 2.44 s. Both engines' annotations say so, to the bit, and name it among the
    reasons; the same annotation of a scene without pressing has no overlap."""
    s = rack(PRESSING_BREAK)
    base = PYTHON.run(s)
    gap, overlap = pair_margins(base, R)
    assert overlap == pytest.approx(5.21e-4, abs=1e-6)
    assert gap is not None and abs(gap) < 1e-12  # racked neighbours that never collide touch
    python = annotate(s, base, simulator=PYTHON, samples=8)
    assert python == annotate(s, base, simulator=AnalyticSimulator(), samples=8)
    assert python.overlap == overlap and not python.stable
    truth = final_state(s, base).model_copy(update={"stability": python})
    assert OVERLAP in truth.unstable_reasons
    calm = scene([(0.5, 0.5, 1.0, 0.0), (1.0, 0.5, 0.0, 0.0)], mu=0.05, horizon=10)
    assert annotate(calm, simulator=PYTHON, samples=8).overlap is None


def test_an_overlap_of_balls_that_never_touched_is_measured_too() -> None:
    """A hand-made outcome in which ball 0 rolls through ball 1 with no event (a missed
    collision): the near-miss gap goes negative and the overlap is the full depth, 2R."""
    run = Segment(0.0, 1.0, (0.5, 0.5), (1.0, 0.0), 0.0)
    rest = Segment(0.0, 1.0, (0.75, 0.5), (0.0, 0.0), 0.0)
    out = Outcome(1.0, {0: (1.5, 0.5), 1: (0.75, 0.5)}, (), {0: (run,), 1: (rest,)})
    gap, overlap = pair_margins(out, R)
    assert gap == pytest.approx(-2 * R) and overlap == pytest.approx(2 * R)
    touched = Event(0.25 - 2 * R, "ball", (0, 1), None, ((0.75 - 2 * R, 0.5), (0.75, 0.5)))
    gap, overlap = pair_margins(Outcome(1.0, out.positions, (touched,), out.segments), R)
    assert gap is None and overlap == pytest.approx(2 * R)


def test_a_copy_over_the_event_budget_counts_unfinished_and_the_tally_goes_on() -> None:
    """Copy 1 bounces between the walls past a budget of 3 events: it is counted unfinished
    (a flip, in no label group, not in the spread) and copy 2 after it is still tallied."""
    s = scene([(0.5, 0.5, 0.01, 0.0), (1.5, 0.2, 0.0, 0.0)], horizon=5)
    pos = np.array([[[0.5, 0.5], [1.5, 0.2]]] * 3)
    vel = np.array([[[0.01, 0.0], [0.0, 0.0]], [[3.0, 0.0], [0.0, 0.0]], [[0.02, 0.0], [0, 0]]])
    base = PYTHON.run(s)
    tally = kernel_tally(s, base, [0, 1], pos, vel, 3)
    assert (tally.unfinished, tally.any_flip, tally.flips) == (1, 1, {UNFINISHED})
    assert tally.counts == {"q1": 0, "q2": 0, "pocketed": 0}
    assert tally.spread == pytest.approx(0.02**2 / (2 * 0.002 * 9.8) - 0.01**2 / (2 * 0.002 * 9.8))


def test_copies_tallied_in_one_set_of_buffers_tally_as_when_run_alone() -> None:
    """tally_copies runs every copy in one set of working arrays and lists; whatever the copy
    before left there (an unfinished run with events still queued, pocketed balls, another
    number of events) must not change the next copy's tally."""
    scenes = [random_scene(6, i, balls=5, speeds=(0.3, 6.0)) for i in range(24)]
    s = scenes[0]
    base = PYTHON.run(s)
    arrays = [perturbation_arrays(other, 0.0, 1) for other in scenes]
    ids = arrays[0][0]
    pos = np.concatenate([a[1] for a in arrays])
    vel = np.concatenate([a[2] for a in arrays])
    together = kernel_tally(s, base, ids, pos, vel, 6)
    alone = [kernel_tally(s, base, ids, p[None], v[None], 6) for p, v in zip(pos, vel, strict=True)]
    assert 0 < together.unfinished < len(scenes)
    assert together.unfinished == sum(t.unfinished for t in alone)
    assert together.any_flip == sum(t.any_flip for t in alone)
    assert together.counts == {g: sum(t.counts[g] for t in alone) for g in together.counts}
    assert together.flips == set().union(*(t.flips for t in alone))
    assert together.spread == max(t.spread for t in alone)


def test_a_copy_chattering_in_a_pressing_contact_makes_the_scene_unstable_not_an_error() -> None:
    """The rack break of the dataset card's known limitation: one perturbed copy squeezes a
    ball between two others at ever shorter intervals (it would run to the 100,000-event
    budget). Kernel and Python engine count it unfinished alike; the scene is unstable for it."""
    s = rack(PRESSING_BREAK).model_copy(update={"scene_id": "break_0"})  # copy 25 chatters
    base = PYTHON.run(s)
    assert copy_budget(len(base.events), PYTHON.max_events) == 1000
    ids, pos, vel = perturbation_arrays(s, 1e-4, 64)
    chatter = unvalidated_copy(s, ids, pos[25].tolist(), vel[25].tolist())
    with pytest.raises(SimulationError, match="more than 20000 events"):
        PYTHON.with_max_events(20_000).run(chatter)
    python = annotate(s, base, simulator=PYTHON)
    assert python == annotate(s, base, simulator=AnalyticSimulator())
    assert not python.stable and "unfinished" in python.flips
    truth = final_state(s, base).model_copy(update={"stability": python})
    assert truth.unstable_reasons[-1] == "unfinished"


@pytest.mark.slow
def test_under_two_per_mille_of_stable_scenes_flip_under_fresh_perturbations() -> None:
    """2,000 generated scenes; each stable one gets 20 fresh perturbations (another stream),
    simulated by the pure-Python engine; a scene counts when any of them flips a label."""
    family, cfg, kernel = BilliardsFamily(), DatasetConfig(), AnalyticSimulator()
    stable: list[Scene] = []
    for i in range(2000):
        made = family.make_scene(cfg, kernel, 5, float(1 + i % 5), i)
        if made.truth.stable:
            stable.append(made.scene)
    assert len(stable) > 1000
    flipped = 0
    for s in stable:
        reference = labels(PYTHON.run(s))
        ids, pos, vel = perturbation_arrays(s, cfg.stability_delta, 20, stream="check")
        flipped += any(
            labels(PYTHON.run(unvalidated_copy(s, ids, p.tolist(), v.tolist()), s.horizon))
            != reference
            for p, v in zip(pos, vel, strict=True)
        )
    assert flipped / len(stable) < 0.002, (flipped, len(stable))
