"""Reference predictions of the billiards family, as
:class:`~bpb_tasks.billiards.truth.final.FinalState` values (the ``baseline`` adapter answers each
task from them):

- ``stasis``: nothing moves and nothing is hit.
- ``straight``: the cue ball rolls with friction and wall reflections (and may drop into a pocket)
  but passes through the other balls, which stay where they are.
- ``random``: T/F labels and on-table positions drawn from the generator the adapter seeds from
  (seed, scene id, task), so reruns give the same answers.

The ``oracle`` (the exact simulation) is the family's own ground truth, not a prediction here.
"""

from __future__ import annotations

import functools
import random
from collections.abc import Callable

from bpb_tasks.billiards.scene.model import WALLS, Scene
from bpb_tasks.billiards.truth.final import BallPosition, FinalState, Q1Label, Q2Label, final_state
from bpb_tasks.simulators.analytic import AnalyticSimulator

Predictor = Callable[[Scene, random.Random], FinalState]


@functools.cache
def _simulator() -> AnalyticSimulator:
    return AnalyticSimulator()


def predict_stasis(scene: Scene, rng: random.Random) -> FinalState:
    """Nothing moves and nothing is hit."""
    return FinalState(
        scene_id=scene.scene_id,
        horizon=scene.horizon,
        q1=[Q1Label(id=b.id, answer="F") for b in scene.balls if b.id != 0],
        q2=[Q2Label(wall=w, answer="F") for w in WALLS],
        predictions=[BallPosition(id=b.id, pos=b.pos) for b in scene.balls],
        simulator="baseline:stasis",
    )


def predict_straight(scene: Scene, rng: random.Random) -> FinalState:
    """The cue ball alone on the table; the others keep their places and are never hit."""
    cue_only = scene.model_copy(update={"balls": [b for b in scene.balls if b.id == 0]})
    outcome = _simulator().run(cue_only)
    alone = final_state(cue_only, outcome, simulator="baseline:straight")
    cue_pos = {p.id: p.pos for p in alone.predictions}.get(0)
    return FinalState(
        scene_id=scene.scene_id,
        horizon=scene.horizon,
        q1=[Q1Label(id=b.id, answer="F") for b in scene.balls if b.id != 0],
        q2=alone.q2,
        predictions=[
            BallPosition(id=b.id, pos=cue_pos if b.id == 0 else b.pos) for b in scene.balls
        ],
        simulator="baseline:straight",
    )


def predict_random(scene: Scene, rng: random.Random) -> FinalState:
    """Coin-flip labels and uniform on-table positions from ``rng``."""
    radius = scene.physics.ball_radius

    def spot() -> tuple[float, float]:
        x = rng.uniform(radius, scene.table.width - radius)
        return (round(x, 4), round(rng.uniform(radius, scene.table.height - radius), 4))

    return FinalState(
        scene_id=scene.scene_id,
        horizon=scene.horizon,
        q1=[Q1Label(id=b.id, answer=rng.choice(("T", "F"))) for b in scene.balls if b.id != 0],
        q2=[Q2Label(wall=w, answer=rng.choice(("T", "F"))) for w in WALLS],
        predictions=[BallPosition(id=b.id, pos=spot()) for b in scene.balls],
        simulator="baseline:random",
    )


PREDICTORS: dict[str, Predictor] = {
    "stasis": predict_stasis,
    "straight": predict_straight,
    "random": predict_random,
}
