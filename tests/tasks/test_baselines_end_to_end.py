"""Generated dataset -> runner with baselines -> scores: oracle is 100%, stasis is exactly what
the ground truth files say nothing-happens earns (computed here straight from final.json)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from bpb_core.dataset import generate_dataset
from bpb_core.layout import FINAL, INIT, iter_scene_keys
from bpb_core.results import load_results
from bpb_core.results.tables import leaderboard
from bpb_core.runner import run_eval
from bpb_core.runner.options import RunOptions
from bpb_tasks.paper.stasis import stasis_index


def expected_stasis(data: Path) -> dict[str, float]:
    """Means over horizons of per-scene stasis scores, from the JSON files alone."""
    per_h: dict[float, dict[str, list[float]]] = {}
    for key in iter_scene_keys(data):
        init = json.loads((key.dir(data) / INIT).read_text())
        final = json.loads((key.dir(data) / FINAL).read_text())
        radius = init["physics"]["ball_radius"]
        start = {b["id"]: b["pos"] for b in init["balls"]}
        q1 = sum(x["answer"] == "F" for x in final["q1"]) / len(final["q1"])
        q2 = float(all(x["answer"] == "F" for x in final["q2"]))
        still = [
            p["pos"] is not None and math.dist(p["pos"], start[p["id"]]) <= radius
            for p in final["predictions"]
        ]
        scores = per_h.setdefault(key.horizon, {"q1": [], "q2": [], "q3": []})
        for task, value in (("q1", q1), ("q2", q2), ("q3", sum(still) / len(still))):
            scores[task].append(value)
    out = {
        task: sum(sum(s[task]) / len(s[task]) for s in per_h.values()) / len(per_h)
        for task in ("q1", "q2", "q3")
    }
    out["total"] = 0.3 * out["q1"] + 0.3 * out["q2"] + 0.4 * out["q3"]
    return out


@pytest.mark.slow
def test_generated_dataset_oracle_and_stasis_runs(tmp_path: Path) -> None:
    data = generate_dataset(tmp_path / "data", 5, [1.0, 3.0], seed=7, workers=1, images=False)
    for name in ("oracle", "stasis"):
        out = tmp_path / "runs" / f"baseline_{name}"
        run_eval(Path(data), f"baseline:{name}", out, RunOptions(input_mode="state"))
    results = load_results(tmp_path / "runs")
    units = results.units
    board = leaderboard(units, results.suites).set_index("run")
    assert board.loc["baseline_oracle", ["q1", "q2", "q3", "total"]].tolist() == [1.0] * 4
    expected = expected_stasis(Path(data))
    for metric, value in expected.items():
        assert board.loc["baseline_stasis", metric] == pytest.approx(value, abs=1e-12)
    index = stasis_index(units).set_index("run")
    assert index.loc["baseline_stasis", "motion_stasis"] == 1.0
    assert index.loc["baseline_oracle", "contact_stasis"] == 0.0
