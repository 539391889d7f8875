"""``bpb bench sim`` library and command on a handful of scenes."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from PIL import Image

from bpb_core.simulate import simulate_lines
from bpb_tasks.simulators import bench_report
from bpb_tasks.simulators.bench import bench_simulators
from bpb_tasks.simulators.bench_scenes import random_scenes

BPB = str(Path(sys.executable).with_name("bpb"))


def test_bench_rows_reference_is_exact_and_analytic_close() -> None:
    result = bench_simulators(scenes=4, seed=3, dts=(1e-2,))
    names = [row.name for row in result.rows]
    assert names == ["mpmath50 (reference)", "analytic", "pymunk dt=0.01"]
    reference, analytic, _ = result.rows
    assert reference.max_error == 0.0 and reference.q1_disagree == 0
    assert analytic.max_error < 1e-9 and analytic.q1_disagree == analytic.pocket_disagree == 0
    assert all(row.ms_per_scene > 0 for row in result.rows)


def test_markdown_section_is_replaced_not_duplicated(tmp_path: Path) -> None:
    result = bench_simulators(scenes=2, seed=1, dts=(1e-2,))
    doc = tmp_path / "benchmarks.md"
    doc.write_text("# Benchmarks\n\n## Start-up\n\nkeep me\n")
    bench_report.update_section(doc, bench_report.markdown(result))
    bench_report.update_section(doc, bench_report.markdown(result))
    text = doc.read_text()
    assert text.count(bench_report.HEADING) == 1 and "keep me" in text
    assert "| analytic |" in text and result.machine in text


def test_bench_sim_command_writes_plot_and_docs(tmp_path: Path) -> None:
    plot, doc = tmp_path / "img" / "bench_sim.png", tmp_path / "benchmarks.md"
    args = ["bench", "sim", "--scenes", "2", "--dts", "1e-2", "--simulate-scenes", "20"]
    done = subprocess.run(
        [BPB, *args, "--plot", str(plot), "--markdown", str(doc)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "pymunk dt=0.01" in done.stdout and "ms/scene" in done.stdout
    with Image.open(plot) as image:
        assert image.size[0] >= 1000
    assert "![speed against error](img/bench_sim.png)" in doc.read_text()


def test_parallel_simulate_lines_keep_input_order(tmp_path: Path) -> None:
    paths = []
    for i, scene in enumerate(random_scenes(40, seed=9)):
        paths.append(tmp_path / f"s{i}.json")
        paths[-1].write_text(scene.model_dump_json())
    paths.reverse()
    one = list(simulate_lines(paths, workers=1))
    two = list(simulate_lines(paths, workers=2))
    assert one == two and len(one) == 40
    assert '"scene_id":"r9_00039"' in one[0]
