"""The ``billiards`` scene family: 7 balls on a 2 m x 1 m table, only the cue ball moving.

Everything core needs to generate, read and check billiards datasets comes through
:class:`BilliardsFamily`: the config model, the sampler (seeded per scene), the simulation with
ground truth and stability annotation, the three images, the index columns and per-horizon
counts, the stats figures, speed calibration, the reference predictions behind the ``baseline``
adapter, reading a scene back from its image (``baseline:vision``), the failure gallery's
picture and the simulator comparison of ``bpb bench sim``.
"""

from __future__ import annotations

import functools
import itertools
import math
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bpb_core.interfaces import Simulator
from bpb_core.picture import ScenePicture
from bpb_core.simulator_spec import parse_spec
from bpb_core.validated_files import validate_mapping
from bpb_tasks.billiards import bench_compare
from bpb_tasks.billiards.render.images import IMAGE_NAMES
from bpb_tasks.billiards.scene.calibrate import Calibration, calibrate_horizon
from bpb_tasks.billiards.scene.config import (
    DatasetConfig,
    horizon_key,
    load_config,
)
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.scene.sampler import build_scene, draw, scene_rng
from bpb_tasks.billiards.truth.final import FinalState, final_state
from bpb_tasks.billiards.truth.outcome import CUE_ID, Outcome

INDEX_COLUMNS = (
    "cue_speed",
    "cue_angle_deg",
    "cue_collision",
    "cue_contacts",
    "cue_walls",
    "pocketed",
    "events",
)

# The words of a published dataset card for billiards scenes (``bpb export --format hf``).
CARD_NAME = "BilliardPhys-Bench scenes"

CARD_DESCRIPTION = """\
Billiards scenes with physics ground truth, for testing whether multimodal models can
predict what happens on a table: seven balls at rest, the cue ball (ball 0) struck with a
given velocity, rolling friction, elastic collisions, six pockets. For each scene and horizon
`t` there are three questions: **q1** which object balls the cue ball touches in `[0, t]`,
**q2** which walls it touches, **q3** where every ball is at `t` (`null` when pocketed).

The image is the scene's input image (the table, numbered balls, the cue velocity as an arrow
with its speed). The prompts state the constants and laws, the horizon and the answer format;
`prompt_image` goes with the image, `prompt_image_state` with the image and the initial state as
JSON, `prompt_state` alone (text only). `target` is the correct answer in the task's JSON format;
`stable` is false when some label flips under a small perturbation of the initial state
(`stability.delta`, 0.1 mm by default; margins in `stability`). Scores follow the paper: q1
per-ball accuracy, q2 exact wall-set match, q3 a ball is right within one radius of the truth;
total = 0.3 q1 + 0.3 q2 + 0.4 q3."""

CARD_CITATION = """\
@misc{wang2026billiardphysbench,
  title  = {BilliardPhys-Bench: Benchmarking Physical Reasoning and Visual Dynamics of
            Multimodal LLMs},
  author = {Wang, Ben and Li, Xiaogang and Gao, Ruochen and Xiao, Peiyao and Xu, Chengliang
            and Wang, Zeyu and Chen, Zichao and Zhao, Bing and Wei, Hu},
  year   = {2026}
}"""


@dataclass(frozen=True)
class MadeScene:
    """A sampled, simulated and annotated scene (implements ``GeneratedScene``)."""

    scene: Scene
    outcome: Outcome
    truth: FinalState
    config: DatasetConfig

    @property
    def row(self) -> dict[str, object]:
        """The family's ``index.csv`` cells."""
        vx, vy = self.scene.ball(CUE_ID).vel
        contacts = sorted(self.outcome.cue_contacts())
        pocketed = sorted(i for i, p in self.outcome.positions.items() if p is None)
        return {
            "cue_speed": round(math.hypot(vx, vy), 6),
            "cue_angle_deg": round(math.degrees(math.atan2(vy, vx)) % 360.0, 6),
            "cue_collision": bool(contacts),
            "cue_contacts": " ".join(map(str, contacts)),
            "cue_walls": " ".join(q.wall for q in self.truth.q2 if q.answer == "T"),
            "pocketed": " ".join(map(str, pocketed)),
            "events": len(self.outcome.events),
        }

    def files(self, images: bool) -> dict[str, bytes]:
        """``init.json``, ``final.json`` and, with ``images``, the three PNGs."""
        blobs = {
            "init.json": (self.scene.model_dump_json(indent=2) + "\n").encode(),
            "final.json": (self.truth.model_dump_json(indent=2) + "\n").encode(),
        }
        if images:
            from bpb_tasks.billiards.render.images import render_pngs

            blobs.update(render_pngs(self.scene, self.outcome, self.config))
        return blobs


@functools.lru_cache(maxsize=64)
def _simulator_name(spec: str) -> str:
    """The simulator's name in a config's ``simulator`` spec (parsed once, not per scene)."""
    return parse_spec(spec, "simulator").name


@dataclass
class BilliardsTally:
    """Per-horizon counts: cue-ball collisions and the cue speeds drawn (for the histogram)."""

    speed_range: tuple[float, float]
    target: float = 0.5
    scenes: int = 0
    collisions: int = 0
    speeds: list[float] = field(default_factory=list)

    def add(self, row: Mapping[str, object]) -> None:
        """Count one kept scene from its index cells."""
        self.scenes += 1
        self.collisions += bool(row["cue_collision"])
        speed = row["cue_speed"]
        assert isinstance(speed, float)
        self.speeds.append(speed)

    def summary(self) -> dict[str, Any]:
        """Collisions, their realised rate beside the calibration target, and the speed range,
        for the manifest."""
        rate = round(self.collisions / self.scenes, 6) if self.scenes else 0.0
        return {
            "cue_collisions": self.collisions,
            "collision_rate": rate,
            "target_collision_rate": self.target,
            "speed_range": self.speed_range,
        }


class BilliardsFamily:
    """Scene family plugin ``billiards`` (see the module docstring)."""

    name = "billiards"
    scene_model = Scene
    truth_model = FinalState
    config_model = DatasetConfig
    input_image = "init.png"
    image_names = IMAGE_NAMES
    index_columns = INDEX_COLUMNS
    predictors = ("stasis", "straight", "random")
    bench_contestants = bench_compare.CONTESTANTS
    bench_reference = bench_compare.REFERENCE
    bench_description = bench_compare.DESCRIPTION
    bench_measures = bench_compare.MEASURES

    def dataset_card(self) -> dict[str, Any]:
        """The words of a published dataset card (``bpb export --format hf``)."""
        return {
            "pretty_name": CARD_NAME,
            "description": CARD_DESCRIPTION,
            "citation": CARD_CITATION,
            "license": "mit",
            "task_categories": ["visual-question-answering"],
            "tags": ["physics", "billiards", "physical-reasoning", "multimodal", "benchmark"],
        }

    def load_config(self, source: Any) -> DatasetConfig:
        """A :class:`DatasetConfig` from a config, a mapping of its fields, a JSON/TOML file or
        ``None`` (the defaults)."""
        if isinstance(source, DatasetConfig):
            return source
        if source is None or isinstance(source, str | Path):
            return load_config(source)
        return validate_mapping(DatasetConfig, source, "config")

    def check_config(self, config: DatasetConfig, horizons: Sequence[float]) -> None:
        """Every horizon needs a cue-speed range (unless calibrated first), and the image
        margins must hold the labels."""
        config.check_margins()
        for horizon in horizons:
            config.speed_range(horizon)

    def simulator_name(self, config: DatasetConfig) -> str:
        """The simulator the config names (``analytic`` by default), with any options
        (``pymunk:dt=0.0005``)."""
        return config.simulator

    def sample(
        self,
        rng: random.Random,
        horizon: float,
        index: int,
        config: DatasetConfig | Mapping[str, Any],
    ) -> Scene:
        """Draw scene ``index`` at ``horizon`` from ``rng`` (normally :func:`scene_rng`)."""
        resolved = self.load_config(config)
        return build_scene(draw(rng, resolved), horizon, index, resolved)

    def make_scene(
        self, config: DatasetConfig, simulator: Simulator, seed: int, horizon: float, index: int
    ) -> MadeScene:
        """Sample, simulate and annotate scene ``index`` at ``horizon``."""
        from bpb_tasks.billiards.stability.annotation import annotate

        scene = self.sample(scene_rng(seed, horizon, index), horizon, index, config)
        outcome: Outcome = simulator.run(scene)
        final = final_state(scene, outcome, _simulator_name(config.simulator))
        stability = annotate(
            scene,
            outcome,
            delta=config.stability_delta,
            samples=config.stability_samples,
            simulator=simulator,
        )
        truth = final.model_copy(update={"stability": stability})
        return MadeScene(scene, outcome, truth, config)

    def physics(self, config: DatasetConfig) -> dict[str, Any]:
        """Physics constants, table and pockets."""
        return {
            **config.physics.model_dump(mode="json"),
            "table": config.table.model_dump(mode="json"),
            "pockets": config.pockets.model_dump(mode="json"),
        }

    def ground_truth(
        self,
        scene: Scene,
        simulator: Simulator,
        horizon: float | None = None,
        *,
        stability: bool,
    ) -> FinalState:
        """``final.json`` of ``scene`` at ``horizon`` (default: its own) from ``simulator``."""
        end = scene.horizon if horizon is None else horizon
        outcome: Outcome = simulator.run(scene, end)
        final = final_state(scene, outcome, simulator=getattr(simulator, "name", "unknown"))
        if not stability:
            return final
        from bpb_tasks.billiards.stability.annotation import annotate

        return final.model_copy(update={"stability": annotate(scene, outcome, simulator=simulator)})

    def ground_truths(
        self, scenes: Sequence[Scene], simulator: Simulator, horizon: float | None = None
    ) -> list[FinalState]:
        """``final.json`` of each scene (no stability), each run of consecutive scenes on one
        table, physics and pockets simulated by one call of the simulator's ``run_many`` when it
        has one (a batch call takes one table)."""
        from bpb_core.capabilities import RunsMany

        outcomes: list[Outcome] = []
        for _, run in itertools.groupby(scenes, lambda s: (s.table, s.physics, s.pockets)):
            group = list(run)
            if isinstance(simulator, RunsMany):
                outcomes += simulator.run_many(group, horizon)
            else:
                outcomes += [simulator.run(scene, horizon) for scene in group]
        name = getattr(simulator, "name", "unknown")
        return [final_state(s, o, name) for s, o in zip(scenes, outcomes, strict=True)]

    def calibrate_horizon(
        self, config: DatasetConfig, simulator: Simulator, horizon: float
    ) -> Calibration:
        """The cue-speed range of ``horizon`` giving the target collision rate."""
        return calibrate_horizon(horizon, config, simulator)

    def apply_calibration(
        self, config: DatasetConfig, results: Mapping[float, Any]
    ) -> tuple[DatasetConfig, dict[str, Any]]:
        """The config with the calibrated ranges, and the manifest's calibration record."""
        found: dict[str, Calibration] = {horizon_key(h): c for h, c in results.items()}
        record = {
            key: {"low": c.range.low, "high": c.range.high, "rate": c.rate, "samples": c.samples}
            for key, c in found.items()
        }
        ranges = {**config.speed_ranges, **{key: c.range for key, c in found.items()}}
        return config.model_copy(update={"speed_ranges": ranges}), record

    def new_tally(self, config: DatasetConfig, horizon: float) -> BilliardsTally:
        """An empty tally for ``horizon``."""
        speeds = config.speed_range(horizon)
        return BilliardsTally((speeds.low, speeds.high), config.calibration.target)

    def write_stats(
        self, root: Path, config: DatasetConfig, tallies: Mapping[float, Any]
    ) -> list[str]:
        """Cue-speed histograms and collision counts per horizon under ``root/stats``."""
        from bpb_tasks.billiards.render.stats_figures import write_stats

        return write_stats(root, tallies)

    def predict(self, name: str, scene: Scene, rng: random.Random) -> FinalState:
        """The ``stasis``, ``straight`` or ``random`` prediction for ``scene``."""
        from bpb_tasks.billiards.truth.predictors import PREDICTORS

        return PREDICTORS[name](scene, rng)

    def perceive(self, image: bytes, prompt: str) -> Scene:
        """The scene read from ``init.png`` and the prompt (``baseline:vision``); raises
        ``ValueError`` saying what could not be read."""
        from bpb_tasks.billiards.vision.perceive import perceive

        return perceive(image, prompt)

    def perception_error(self, perceived: Scene, scene: Scene) -> dict[str, float]:
        """Centre error (mm, mean and max over balls), cue speed (m/s) and direction (degrees)
        errors of a perceived scene."""
        from bpb_tasks.billiards.vision.perceive import perception_error

        return perception_error(perceived, scene)

    def perception_ceiling(
        self, image: bytes, prompt: str, scene: Scene, simulator: Simulator
    ) -> dict[str, bool]:
        """Which labels survive the image's pixel grid (true centres snapped to the pixel
        each ball is drawn at, true velocities): ``pixel_ceiling_q1_set``, ``pixel_ceiling_q2``;
        see :func:`bpb_tasks.billiards.vision.perceive.perception_ceiling`."""
        from bpb_tasks.billiards.vision.perceive import perception_ceiling

        def truth_of(s: Scene) -> FinalState:
            return self.ground_truth(s, simulator, stability=False)

        return perception_ceiling(image, prompt, scene, truth_of)

    def picture(self, dataset: Path, folder: Path, scene: Scene) -> ScenePicture:
        """The scene's trajectory image (or a plain table) for the failure gallery."""
        from bpb_tasks.billiards.render.images import scene_picture

        return scene_picture(dataset, folder, scene)

    def bench_scenes(self, count: int, seed: int) -> list[Scene]:
        """``count`` random 7-ball scenes of the stream ``seed`` (``bpb bench sim``)."""
        return list(bench_compare.random_scenes(count, seed))

    def compare(self, outcome: Outcome, reference: Outcome, scene: Scene) -> dict[str, float]:
        """Final-position error and label disagreements of ``outcome`` against ``reference``."""
        return bench_compare.compare(outcome, reference, scene)

    def events(self, outcome: Outcome) -> int:
        """Events in the outcome's log (ball, wall, pocket and stop events)."""
        return len(outcome.events)

    def scaled_scene(self, scene: Scene, factor: float) -> Scene:
        """``scene`` with every velocity times ``factor`` (more events in the same time)."""
        return bench_compare.scaled_scene(scene, factor)
