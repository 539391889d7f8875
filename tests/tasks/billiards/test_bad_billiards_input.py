"""The billiards rows of the bad-input catalogue: configs and scenes bpb would reject later (or
never finish) are refused at once, exit 2, with one line naming the file and the field."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from support.runner_scenes import make_scene

BPB = str(Path(sys.executable).with_name("bpb"))

CONFIGS = [
    ("g.toml", "[physics]\ng = 1e400\n", "physics.g: Input should be a finite number"),
    ("g.json", '{"physics": {"g": 1e400}}', "physics.g: Input should be a finite number"),
    ("mu.toml", "[physics]\nmu = nan\n", "physics.mu: Input should be a finite number"),
    ("r.toml", "[physics]\nball_radius = inf\n", "physics.ball_radius: Input should be a finite"),
    ("speed.toml", '[speed_ranges."1"]\nlow = 1\nhigh = 1e300\n',
     "speed_ranges.1.high: Input should be less than or equal to 100"),
    ("table.toml", "[table]\nwidth = 100\n", "table.width: 100 m at image.px_per_m 600 makes"),
    ("mug.toml", "[physics]\nmu = 1e308\n", "physics: mu*g = 1e+308 * 9.8 overflows"),
    ("key.json", '{"speed_ranges": {"abc": {"low": 1, "high": 2}}}',
     "speed_ranges: key 'abc' is not a horizon in seconds (a positive number)"),
    ("key0.toml", '[speed_ranges."0"]\nlow = 1\nhigh = 2\n',
     "speed_ranges: key '0' is not a horizon in seconds"),
    ("keys.toml", '[speed_ranges."1"]\nlow = 1\nhigh = 2\n'
     '[speed_ranges."1.0"]\nlow = 1\nhigh = 3\n',
     "speed_ranges: key '1.0' repeats horizon 1"),
    ("sim.json", '{"simulator": "nope"}',
     "simulator: unknown simulator 'nope'; known simulators:"),
    ("family.toml", 'family = "nope"\n', "family: 'nope', but the scene family is 'billiards'"),
    ("h1.toml", '[speed_ranges."2"]\nlow = 1\nhigh = 2\n',
     "speed_ranges: no cue-speed range for horizon 1 s (have 2)"),
    ("margins.toml", "[image]\nmargin_left = 40\n", "image.margin_left: 40 px cuts off the "
     "image's labels or pockets at px_per_m 600 with pockets of radius 0.06 m (needs at least 116"),
    ("calibration.toml", "[calibration]\nsamples = 1_000_000_000\n",
     "calibration.samples: Input should be less than or equal to 200000"),
    # pockets that cover the table leave no place for a ball: the hint must name them
    ("pockets.toml", "[pockets]\nradius = 0.75\n",
     "balls: could not place ball 0 of 7 clear of the other balls and the pockets; use fewer or "
     "smaller balls, a smaller min_gap, or smaller pockets (pockets.radius, pocket_margin)"),
    # pymunk's step (1e-3 s) would carry these balls through a cushion: the scene, the bound,
    # and where dt is set (bpb generate has no --dt flag)
    ("pymunk.toml", 'simulator = "pymunk"\n[speed_ranges."1"]\nlow = 20\nhigh = 30\n',
     "scene h1_0000: dt: 0.001 s is above this scene's stability bound, 0.000559 s"),
    ("pymunk.json", '{"simulator": "pymunk:dt=0.002", "speed_ranges": {"1": {"low": 20, '
     '"high": 30}}}', "scene h1_0000: dt: 0.002 s is above this scene's stability bound, 0.000559 "
     "s (half the ball radius, 0.0142875 m, over the fastest possible speed, 25.52 m/s): a longer "
     "step can carry a ball through a cushion; the simulator cannot finish it: set dt in the "
     "config's simulator 'pymunk:dt=0.002' (pymunk:dt=...)"),
    # the simulator's options, as bpb bench sim takes contestants: checked before any scene
    ("spec.toml", 'simulator = "pymunk:dt"\n',
     "simulator 'pymunk:dt': expected name or name:key=value,... (each key once)"),
    ("twice.toml", 'simulator = "pymunk:dt=0.001,dt=0.002"\n',
     "simulator 'pymunk:dt=0.001,dt=0.002': expected name or name:key=value,... (each key once)"),
    ("dt.toml", 'simulator = "pymunk:dt=-1"\n',
     "simulator 'pymunk:dt=-1': dt: must be a positive finite number of seconds, got -1"),
    ("dt.json", '{"simulator": "pymunk:dt=fast"}',
     "simulator 'pymunk:dt=fast': dt: must be a positive finite number of seconds, got 'fast'"),
    ("option.toml", 'simulator = "analytic:dt=0.001"\n',
     "simulator 'analytic:dt=0.001': simulator 'analytic': does not accept dt: "),
    ("wide.toml", "[table]\nwidth = 1e300\n", "table.width: 1e+300 m at image.px_per_m 600 makes "
     "a 6e+302 px image side (at most 20,000)"),
    # each side within 20,000 px, but 363 million pixels: gigabytes per image, minutes per scene
    ("area.toml", "[table]\nwidth = 6.6\nheight = 6\n[image]\npx_per_m = 3000\n",
     "image: the table at px_per_m 3000 plus the margins makes a 20,620 x 18,900 px image"),
    ("margin.json", '{"image": {"margin_left": 100000}}',
     "image: the table at px_per_m 600 plus the margins makes a 101,248 x 780 px image"),
    # no coercion: true is not 1 ball, "0.01" not a number, 12.0 not a count
    ("bool.toml", "balls = true\n", "balls: Input should be a valid integer"),
    ("text.json", '{"physics": {"mu": "0.01"}}', "physics.mu: Input should be a valid number"),
    ("count.toml", "[calibration]\nsamples = 100.0\n",
     "calibration.samples: Input should be a valid integer"),
    ("name.toml", "simulator = 1\n", "simulator: Input should be a valid string"),
]  # fmt: skip


def _one_line(done: subprocess.CompletedProcess[str]) -> str:
    assert done.returncode == 2, done.stderr
    line = done.stderr.strip()
    assert "\n" not in line, line
    return line


@pytest.mark.parametrize(("name", "text", "expected"), CONFIGS, ids=[c[0] for c in CONFIGS])
def test_bad_config_is_one_line_exit_2(name: str, text: str, expected: str, tmp_path: Path) -> None:
    config = tmp_path / name
    config.write_text(text)
    done = subprocess.run([BPB, "generate", "--out", str(tmp_path / "ds"), "--config",
                           str(config), "--horizons", "1", "--per-horizon", "1", "--no-images"],
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert f"{config}: {expected}" in _one_line(done)
    assert not (tmp_path / "ds").exists()


def test_a_config_that_is_not_utf8_is_one_line_exit_2(tmp_path: Path) -> None:
    config = tmp_path / "latin1.toml"
    config.write_bytes("# r\xe9glages\nballs = 3\n".encode("latin-1"))
    done = subprocess.run([BPB, "generate", "--out", str(tmp_path / "ds"), "--config",
                           str(config), "--horizons", "1", "--per-horizon", "1", "--no-images"],
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert f"{config}: cannot read config: not UTF-8 text" in _one_line(done)


@pytest.mark.slow
def test_a_config_whose_scenes_never_end_names_the_scene(tmp_path: Path) -> None:
    config = tmp_path / "endless.toml"  # no friction, no pockets: bounces up to the event cap
    config.write_text('[physics]\nmu = 0.0\n[pockets]\nradius = 0.0\n'
                      '[speed_ranges."100000"]\nlow = 1\nhigh = 2\n')  # fmt: skip
    done = subprocess.run([BPB, "generate", "--out", str(tmp_path / "ds"), "--config",
                           str(config), "--horizons", "100000", "--per-horizon", "1",
                           "--no-images", "--workers", "1"],
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    line = _one_line(done)
    assert f"{config}: scene h100000_0000: more than 100000 events before t=100000" in line
    assert not (tmp_path / "ds").exists()


def _scene(**change: Any) -> dict[str, Any]:
    scene: dict[str, Any] = json.loads(make_scene(1.0, 0).model_dump_json())
    scene.update(change)
    return scene


def _bouncer() -> dict[str, Any]:
    """A frictionless cue ball bouncing between the cushions at x = 0.5, away from pockets and
    balls: it never rests, so a long horizon holds more events than any cap."""
    balls = [{"id": 0, "pos": [0.5, 0.5], "vel": [0.0, 1.0]}, {"id": 1, "pos": [1.5, 0.5]}]
    return _scene(physics={"mu": 0.0}, balls=balls)


SCENES = [
    ("nocue", lambda: _scene(balls=[b for b in _scene()["balls"] if b["id"] != 0]), [],
     "balls: no cue ball (a ball with id 0)"),
    ("fast", lambda: _scene(balls=[{"id": 0, "pos": [1.0, 0.5], "vel": [1e154, 0.0]}]), [],
     "balls[0].vel: speed 1e+154 m/s is above 100 m/s"),
    ("huge-g", lambda: _scene(physics={"g": float("inf")}), [],
     "physics.g: Input should be a finite number"),
    *[(f"huge-mu{'-'.join(['', *args])}", lambda: _scene(physics={"mu": 1e308}), args,
       "physics: mu*g = 1e+308 * 9.8 overflows (not a finite deceleration in m/s^2)")
      for args in ([], ["--engine", "kernel"], ["--engine", "python"], ["--simulator", "pymunk"])],
    # pymunk's step budget names where dt is set, as its bound refusal does
    ("pymunk-mu0", _bouncer, ["--simulator", "pymunk", "--horizon", "1e9"],
     "--dt: 1e+12 steps of 0.001 s to reach t=1e+09 with balls still moving"),
    ("pymunk-small-dt", _bouncer, ["--simulator", "pymunk", "--dt", "5e-8"],
     "--dt: 2e+07 steps of 5e-08 s to reach t=1 with balls still moving (at most 10,000,000); "
     "use a shorter horizon or a larger dt"),
    ("pymunk-huge-horizon", _scene, ["--simulator", "pymunk", "--horizon", "1e308"],
     "--dt: t=1e+308 is more steps of 0.001 s than can be counted; use a horizon under"),
    ("pymunk-huge-horizon-in-file", lambda: _scene(horizon=1e308), ["--simulator", "pymunk"],
     "--dt: t=1e+308 is more steps of 0.001 s than can be counted; use a horizon under"),
    ("event-cap", _bouncer, ["--horizon", "1e9"], "more than 100000 events before t=1000000000"),
    # no coercion: "0" is no ball id, so this scene has no cue ball
    ("text-id", lambda: _scene(balls=[{"id": "0", "pos": [1.0, 0.5], "vel": [1.0, 0.0]}]), [],
     "balls[0].id: Input should be a valid integer"),
]  # fmt: skip


@pytest.mark.parametrize(("name", "build", "args", "expected"), SCENES, ids=[s[0] for s in SCENES])
def test_bad_scene_is_one_line_exit_2_naming_the_file(
    name: str, build: Any, args: list[str], expected: str, tmp_path: Path
) -> None:
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(build()).replace("Infinity", "1e400"))
    done = subprocess.run([BPB, "simulate", str(path), *args], capture_output=True, text=True,
                          timeout=120)  # fmt: skip
    assert f"{path}: {expected}" in _one_line(done)
