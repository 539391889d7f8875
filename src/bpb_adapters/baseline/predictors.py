"""What each baseline predicts for a scene, as a :class:`~bpb_core.scene.FinalState`.

- ``stasis``: nothing moves and nothing is hit.
- ``straight``: the cue ball rolls with friction and wall reflections (and may drop into a pocket)
  but passes through the other balls, which stay where they are.
- ``random``: T/F labels and on-table positions drawn from a generator seeded from
  (seed, scene id, task), so reruns give the same answers.
- ``oracle``: the exact analytic simulation of the scene (the ceiling; must score 100%).
"""

from __future__ import annotations

import random
from collections.abc import Callable
from typing import Any

from bpb_core.outcome import final_state
from bpb_core.scene import WALLS, BallPosition, FinalState, Q1Label, Q2Label, Scene

Predictor = Callable[[Scene, random.Random], FinalState]


def _simulator() -> Any:
    from bpb_core.registry import make_registry

    return make_registry().simulator("analytic")


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


class OraclePredictor:
    """The exact simulation of the full scene (builds the analytic simulator once)."""

    def __init__(self) -> None:
        self._sim = _simulator()

    def __call__(self, scene: Scene, rng: random.Random) -> FinalState:
        return final_state(scene, self._sim.run(scene), simulator="baseline:oracle")


class StraightPredictor:
    """The cue ball alone on the table; the others keep their places and are never hit."""

    def __init__(self) -> None:
        self._sim = _simulator()

    def __call__(self, scene: Scene, rng: random.Random) -> FinalState:
        cue_only = scene.model_copy(update={"balls": [b for b in scene.balls if b.id == 0]})
        outcome = self._sim.run(cue_only)
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


PREDICTORS: dict[str, Callable[[], Predictor]] = {
    "stasis": lambda: predict_stasis,
    "straight": StraightPredictor,
    "random": lambda: predict_random,
    "oracle": OraclePredictor,
}
