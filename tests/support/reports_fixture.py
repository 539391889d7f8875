"""A small hand-made dataset and run folders whose scores are worked out by hand.

Four scenes (h1_0000, h1_0001, h2_0000, h2_0001); ball k starts at (0.3 + 0.2 k, 0.5). Ground
truth is written by hand (no simulator) so every expected number below follows from it:

========  ===========  ===============  ==========================================
scene     Q1 true T    Q2 true T        moved > R (Q3)
========  ===========  ===============  ==========================================
h1_0000   {1}          {}               0, 1
h1_0001   {}           {TOP}            0 (ball 3 moved 0.01 m < R: not moved)
h2_0000   {1, 2}       {LEFT, TOP}      0, 1, 2 (2 pocketed); scene marked unstable
h2_0001   {}           {}               0
========  ===========  ===============  ==========================================
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from bpb_core.layout import scene_dir, scene_id
from bpb_tasks.billiards.scene.model import WALLS, Ball, Scene
from bpb_tasks.billiards.truth.final import BallPosition, FinalState, Q1Label, Q2Label, Stability
from support.questions import questions

Pos = tuple[float, float]
START: dict[int, Pos] = {k: (0.3 + 0.2 * k, 0.5) for k in range(7)}
TRUTH: dict[str, dict[str, Any]] = {
    "h1_0000": {"q1": {1}, "q2": set(), "moves": {0: (0.45, 0.5), 1: (0.75, 0.6)}},
    "h1_0001": {
        "q1": set(),
        "q2": {"TOP"},
        "moves": {0: (0.3, 0.8), 3: (0.91, 0.5)},
    },
    "h2_0000": {
        "q1": {1, 2},
        "q2": {"LEFT", "TOP"},
        "moves": {0: (0.2, 0.3), 1: (0.5, 0.9), 2: None},
        "unstable": True,
    },
    "h2_0001": {"q1": set(), "q2": set(), "moves": {0: (1.9, 0.9)}},
}
SCENES = [(1.0, 0), (1.0, 1), (2.0, 0), (2.0, 1)]

_TASKS = questions()


def make_scene(horizon: float, index: int) -> Scene:
    balls = [Ball(id=k, pos=START[k], vel=(1.0, 0.0) if k == 0 else (0.0, 0.0)) for k in START]
    return Scene(scene_id=scene_id(horizon, index), horizon=horizon, balls=balls)


def make_final(scene: Scene, truth: dict[str, dict[str, Any]] = TRUTH) -> FinalState:
    spec = truth[scene.scene_id]
    positions = {k: spec["moves"].get(k, START[k]) for k in START}
    return FinalState(
        scene_id=scene.scene_id,
        horizon=scene.horizon,
        q1=[Q1Label(id=k, answer="T" if k in spec["q1"] else "F") for k in range(1, 7)],
        q2=[Q2Label(wall=w, answer="T" if w in spec["q2"] else "F") for w in WALLS],
        predictions=[BallPosition(id=k, pos=positions[k]) for k in START],
        stability=Stability(stable=not spec.get("unstable", False), delta=1e-4),
    )


def write_dataset(
    root: Path,
    scenes: Sequence[tuple[float, int]] = SCENES,
    truth: dict[str, dict[str, Any]] = TRUTH,
) -> Path:
    """The dataset of ``scenes`` (horizon, index), ground truth from ``truth[scene_id]``."""
    for horizon, index in scenes:
        folder = scene_dir(root, horizon, index)
        folder.mkdir(parents=True)
        scene = make_scene(horizon, index)
        (folder / "init.json").write_text(scene.model_dump_json())
        (folder / "final.json").write_text(make_final(scene, truth).model_dump_json())
    (root / "dataset.json").write_text(json.dumps({"name": "hand-made"}))
    return root


def write_run(
    root: Path,
    adapter: str,
    dataset: Path,
    answers: dict[tuple[str, str], dict[str, Any] | None],
    tasks: tuple[str, ...] = ("q1", "q2", "q3"),
    scenes: Sequence[tuple[float, int]] = SCENES,
) -> Path:
    """``answers[(scene_id, task)]`` is the record to write (None: no file, i.e. missing);
    ``tasks``: the tasks the run was asked; ``scenes``: the dataset's (horizon, index)."""
    root.mkdir(parents=True)
    manifest = {"adapter": adapter, "model_id": adapter, "tasks": list(tasks)}
    manifest["data"] = str(dataset)
    (root / "run.json").write_text(json.dumps(manifest))
    for horizon, index in scenes:
        sid = scene_id(horizon, index)
        for task in tasks:
            record = answers.get((sid, task), {"status": "missing"})
            if record.get("status") == "missing":
                continue
            folder = scene_dir(root, horizon, index)
            folder.mkdir(parents=True, exist_ok=True)
            full = {"scene_id": sid, "horizon": horizon, "index": index, "task": task}
            full |= {"adapter": adapter, "status": "ok", "rule": "first", "finish_reason": "stop"}
            full |= {"attempts": 1, "cost": 0.0, "latency": 0.01, "error": None}
            full |= {"input_mode": "image", "cot": task != "q3"}
            full |= {"usage": {"input_tokens": 100, "output_tokens": 20}}
            full |= record
            (folder / f"{task}.json").write_text(json.dumps(full))
    return root


def oracle_answer(sid: str, task: str) -> dict[str, Any]:
    horizon, index = float(sid[1]), int(sid[-4:])
    return _TASKS[task].expected(make_final(make_scene(horizon, index)))


def stasis_answer(sid: str, task: str) -> dict[str, Any]:
    if task == "q1":
        return {"answers": [{"id": k, "answer": "F"} for k in range(1, 7)]}
    if task == "q2":
        return {"answers": [{"wall": w, "answer": "F"} for w in WALLS]}
    return {"predictions": [{"id": k, "pos": list(START[k])} for k in START]}


def all_answers(make: Any) -> dict[tuple[str, str], dict[str, Any] | None]:
    return {
        (f"h{h:g}_{i:04d}", t): {"answer": make(f"h{h:g}_{i:04d}", t)}
        for h, i in SCENES
        for t in ("q1", "q2", "q3")
    }


def model_answers() -> dict[tuple[str, str], dict[str, Any] | None]:
    """h1_0000 and h2_0001 answered like the oracle; h1_0001: q1 api_error, q2 parse_error,
    q3 answered like stasis; h2_0000 has no files at all (missing)."""
    out: dict[tuple[str, str], dict[str, Any] | None] = {}
    for sid in ("h1_0000", "h2_0001"):
        for task in ("q1", "q2", "q3"):
            out[(sid, task)] = {"answer": oracle_answer(sid, task)}
    out[("h1_0001", "q1")] = {"status": "api_error", "answer": None, "attempts": 4, "cost": None}
    out[("h1_0001", "q2")] = {"status": "parse_error", "answer": None, "attempts": 3}
    out[("h1_0001", "q3")] = {
        "answer": stasis_answer("h1_0001", "q3"),
        "usage": {"input_tokens": 100, "output_tokens": 20, "reasoning_tokens": 50},
    }
    return out


def write_runs(root: Path) -> Path:
    """``root/data`` and ``root/runs`` holding the oracle, stasis and model run folders."""
    data = write_dataset(root / "data")
    runs = root / "runs"
    write_run(runs / "baseline_oracle", "baseline:oracle", data, all_answers(oracle_answer))
    write_run(runs / "baseline_stasis", "baseline:stasis", data, all_answers(stasis_answer))
    write_run(runs / "litellm_model", "litellm:model", data, model_answers())
    return runs
