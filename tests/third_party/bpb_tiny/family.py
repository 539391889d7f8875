"""The ``slider`` scene family: one puck on a 1-D track with friction and two elastic walls.

It provides what every family must (models, config, sampler, ground truth) and four of the
optional capabilities: a manifest summary (:class:`~bpb_core.interfaces.Tallying`), a stats
figure (:class:`~bpb_core.interfaces.DrawingStats`), the ``stasis`` baseline
(:class:`~bpb_core.interfaces.Predicting`) and the gallery picture
(:class:`~bpb_core.interfaces.Picturing`). It has nothing to calibrate.
"""

from __future__ import annotations

import hashlib
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bpb_core.errors import BadInput
from bpb_core.interfaces import Simulator
from bpb_core.layout import scene_id
from bpb_core.picture import ScenePicture
from bpb_tiny.config import SliderConfig, load_config
from bpb_tiny.physics import STABILITY_DT, Outcome
from bpb_tiny.scene import SliderScene, SliderTruth
from bpb_tiny.stats import SliderTally, write_stats

INDEX_COLUMNS = ("x0", "v0", "bounces", "final_x")


def scene_rng(seed: int, horizon: float, index: int) -> random.Random:
    """The generator of one scene, seeded from (seed, horizon, index) alone."""
    digest = hashlib.sha256(f"slider:{seed}:{horizon!r}:{index}".encode()).digest()
    return random.Random(int.from_bytes(digest[:8], "big"))


def sample(config: SliderConfig, seed: int, horizon: float, index: int) -> SliderScene:
    """Draw scene ``index`` at ``horizon``: position, speed, then direction."""
    rng = scene_rng(seed, horizon, index)
    span = config.length * config.margin
    x0 = rng.uniform(span, config.length - span)
    speed = rng.uniform(config.speed_low, config.speed_high)
    v0 = speed if rng.random() < 0.5 else -speed
    return SliderScene(
        scene_id=scene_id(horizon, index),
        horizon=horizon,
        length=config.length,
        mu_g=config.mu_g,
        x0=round(x0, config.decimals),
        v0=round(v0, config.decimals),
    )


def truth_of(
    scene: SliderScene, simulator: Simulator, horizon: float, stability: bool
) -> SliderTruth:
    """``final.json``: the outcome at ``horizon``, and its stability when asked."""
    end: Outcome = simulator.run(scene, horizon)
    stable = None
    if stability:
        early: Outcome = simulator.run(scene, max(horizon - STABILITY_DT, 0.0))
        late: Outcome = simulator.run(scene, horizon + STABILITY_DT)
        stable = early.bounces == late.bounces
    return SliderTruth(
        scene_id=scene.scene_id,
        horizon=horizon,
        simulator=getattr(simulator, "name", "unknown"),
        x=round(end.x, 6),
        bounces=end.bounces,
        hit_times=[round(t, 6) for t in end.hit_times],
        stable=stable,
    )


@dataclass(frozen=True)
class MadeSlider:
    """A sampled and simulated scene (implements ``GeneratedScene``)."""

    scene: SliderScene
    truth: SliderTruth

    @property
    def row(self) -> dict[str, object]:
        """The family's ``index.csv`` cells."""
        return {
            "x0": self.scene.x0,
            "v0": self.scene.v0,
            "bounces": self.truth.bounces,
            "final_x": self.truth.x,
        }

    def files(self, images: bool) -> dict[str, bytes]:
        """``init.json``, ``final.json`` and, with ``images``, ``init.png``."""
        blobs = {
            "init.json": (self.scene.model_dump_json(indent=2) + "\n").encode(),
            "final.json": (self.truth.model_dump_json(indent=2) + "\n").encode(),
        }
        if images:
            from bpb_tiny.render import init_png

            blobs["init.png"] = init_png(self.scene)
        return blobs


class SliderFamily:
    """Scene family plugin ``slider`` (see the module docstring)."""

    name = "slider"
    scene_model = SliderScene
    truth_model = SliderTruth
    config_model = SliderConfig
    input_image = "init.png"
    image_names = ("init.png",)
    index_columns = INDEX_COLUMNS
    predictors = ("stasis",)

    def load_config(self, source: Any) -> SliderConfig:
        """A config from ``None``, a file, a mapping of fields or a config."""
        return load_config(source)

    def check_config(self, config: SliderConfig, horizons: Sequence[float]) -> None:
        """Horizons must not exceed ``max_horizon``."""
        for horizon in horizons:
            if horizon > config.max_horizon:
                raise BadInput(
                    f"config: max_horizon: horizon {horizon:g} s is beyond {config.max_horizon:g} s"
                )

    def simulator_name(self, config: SliderConfig) -> str:
        """The simulator the config names (``slider-exact``)."""
        return config.simulator

    def make_scene(
        self, config: SliderConfig, simulator: Simulator, seed: int, horizon: float, index: int
    ) -> MadeSlider:
        """Sample, simulate and annotate scene ``index`` at ``horizon``."""
        scene = sample(config, seed, horizon, index)
        return MadeSlider(scene, truth_of(scene, simulator, horizon, stability=True))

    def physics(self, config: SliderConfig) -> dict[str, Any]:
        """The world of the config, for the manifest."""
        return {"length": config.length, "mu_g": config.mu_g, "walls": "elastic", "puck": "point"}

    def ground_truth(
        self,
        scene: SliderScene,
        simulator: Simulator,
        horizon: float | None = None,
        *,
        stability: bool,
    ) -> SliderTruth:
        """``final.json`` of ``scene`` at ``horizon`` (default: its own)."""
        end = scene.horizon if horizon is None else horizon
        return truth_of(scene, simulator, end, stability)

    def new_tally(self, config: SliderConfig, horizon: float) -> SliderTally:
        """An empty tally (Tallying)."""
        return SliderTally()

    def write_stats(
        self, root: Path, config: SliderConfig, tallies: Mapping[float, Any]
    ) -> list[str]:
        """The bounce-count figure under ``root/stats`` (DrawingStats)."""
        return write_stats(root, tallies)

    def predict(self, name: str, scene: SliderScene, rng: random.Random) -> SliderTruth:
        """``stasis``: the puck stays where it starts and hits nothing (Predicting)."""
        if name != "stasis":
            raise KeyError(name)
        return SliderTruth(
            scene_id=scene.scene_id, horizon=scene.horizon, simulator=name, x=scene.x0, bounces=0
        )

    def picture(self, dataset: Path, folder: Path, scene: SliderScene) -> ScenePicture:
        """The scene at t = 0, drawn afresh (Picturing)."""
        from bpb_tiny.render import draw_scene

        return draw_scene(scene)
