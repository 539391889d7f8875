"""``bpb bench sim``: contestants of any comparing scene family against its reference (the
command runs in-process, through ``main``)."""

from __future__ import annotations

import math
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from PIL import Image

from bpb_core.bench import sim_report
from bpb_core.bench.sim import bench_family, bench_simulators, build_simulators, with_scaling
from bpb_core.bench.sim_report import SimBench, SimRow
from bpb_core.errors import BadInput, UnknownName
from bpb_core.hookspecs import hookimpl
from bpb_core.registry import Registry, SceneFamilyInfo, SimulatorInfo, make_registry
from bpb_core.simulate import simulate_lines
from bpb_core.simulator_spec import parse_spec
from bpb_tasks.billiards.bench_compare import random_scenes


def test_a_contestant_spec_has_typed_options() -> None:
    assert parse_spec("analytic", "--contestant").options == {}
    entry = parse_spec("pymunk:dt=0.01,precision=50,mode=fast", "--contestant")
    assert entry.name == "pymunk" and entry.spec == "pymunk:dt=0.01,precision=50,mode=fast"
    assert entry.options == {"dt": 0.01, "precision": 50, "mode": "fast"}
    with pytest.raises(BadInput, match="--contestant 'pymunk:dt': expected name or name:key=value"):
        parse_spec("pymunk:dt", "--contestant")


def test_bench_help_lists_sim(bench: Callable[..., Any]) -> None:
    done = bench("--help")
    assert done.returncode == 0 and "sim " in done.stdout


def test_unknown_benchmark_is_a_usage_error(bench: Callable[..., Any]) -> None:
    done = bench("generate")  # a script in benchmarks/ now, no command
    assert done.returncode == 2 and "generate" in done.stderr


def test_billiards_reference_is_exact_and_analytic_close(registry: Registry) -> None:
    result = bench_simulators(4, 3, ("analytic", "pymunk:dt=0.01"), registry=registry)
    assert [row.name for row in result.rows] == [
        "analytic:precision=50",
        "analytic",
        "pymunk:dt=0.01",
    ]
    assert [row.reference for row in result.rows] == [True, False, False]
    assert result.columns == ("q1", "q2", "pocketed", "q3")
    reference, analytic, pymunk = result.rows
    assert reference.max_error == 0.0 and not any(reference.counts.values())
    assert analytic.max_error < 1e-9 and not any(analytic.counts.values())
    assert pymunk.median_error > 1e3 * analytic.median_error
    assert all(row.ms_per_scene > 0 for row in result.rows)


def test_billiards_default_contestants_measure_pymunk_on_fast_scenes(registry: Registry) -> None:
    # after pymunk learned to refuse coarse steps, the default pymunk:dt=0.01 refused every
    # scene with a cue over 1.43 m/s (most --scaling scenes): it is measured, not refused
    family = bench_family(registry, "billiards").family
    reference = build_simulators(
        registry, "billiards", [parse_spec(family.bench_reference, "--reference")]
    )
    specs = [parse_spec(c, "--contestant") for c in family.bench_contestants]
    sims = build_simulators(registry, "billiards", specs)
    for scene in family.bench_scenes(2, 0):
        fast = family.scaled_scene(scene, 8.0)  # cue at 0.8-9.6 m/s
        truth = next(iter(reference.values())).run(fast)
        errors = {
            label: family.compare(sim.run(fast), truth, fast)["error"]
            for label, sim in sims.items()
        }
        assert all(math.isfinite(e) for e in errors.values()), errors


def test_kernel_and_python_engine_side_by_side_with_events_batches_and_scaling(
    registry: Registry,
) -> None:
    contestants = ("analytic:engine=kernel", "analytic:engine=python")
    result = bench_simulators(6, 1, contestants, registry=registry, reference_scenes=2)
    assert result.compared == 2 and result.scenes == 6
    _, kernel, python = result.rows
    assert kernel.max_error == python.max_error < 1e-9  # same float64 arithmetic
    assert kernel.us_per_event and python.us_per_event and kernel.batch_ms and python.batch_ms
    scaled = with_scaling(result, contestants[:1], 3, (1.0, 8.0), registry=registry)
    slow, fast = scaled.scaling
    assert (slow.factor, fast.factor) == (1.0, 8.0)
    assert fast.events_per_scene > 2 * slow.events_per_scene > 0
    text = sim_report.markdown(scaled, None)
    assert "first 2 scenes only" in text and "| 8 |" in text and "µs/event" in text


def test_a_contestant_of_another_family_or_unknown_is_refused(registry: Registry) -> None:
    with pytest.raises(UnknownName, match="nosuch"):
        bench_simulators(1, contestants=("nosuch",), registry=registry)
    with pytest.raises(BadInput, match="dt"):
        bench_simulators(1, contestants=("analytic:dt=0.1",), registry=registry)


# A scene family that is not billiards: a point moving at constant speed on a line.
@dataclass(frozen=True)
class Mover:
    scene_id: str
    horizon: float
    x: float
    v: float


class Exact:
    name = "exact"

    def run(self, scene: Mover, horizon: float | None = None) -> float:
        return scene.x + scene.v * (scene.horizon if horizon is None else horizon)


class Stepper(Exact):
    name = "stepper"

    def __init__(self, dt: float = 0.1) -> None:
        self.dt = dt

    def run(self, scene: Mover, horizon: float | None = None) -> float:
        steps = int((scene.horizon if horizon is None else horizon) / self.dt)
        return scene.x + scene.v * steps * self.dt


class Line:
    name = "line"
    bench_contestants = ("exact", "stepper:dt=0.3")
    bench_reference = "exact"
    bench_description = "points moving on a line"
    bench_measures = "error = distance; past = scenes ending on the other side of 0"

    def bench_scenes(self, count: int, seed: int) -> list[Mover]:
        return [Mover(f"s{i}", 1.0 + i, -0.95 if i == 0 else i, 1.0 + seed) for i in range(count)]

    def compare(self, outcome: float, reference: float, scene: Any) -> dict[str, float]:
        return {"error": abs(outcome - reference), "past": float((outcome > 0) != (reference > 0))}


class LinePlugin:
    @hookimpl
    def bpb_scene_families(self) -> list[SceneFamilyInfo]:
        return [SceneFamilyInfo("line", lambda: Line, "points on a line", default=True)]

    @hookimpl
    def bpb_simulators(self) -> list[SimulatorInfo]:
        return [
            SimulatorInfo("exact", lambda: Exact, "closed form", family="line"),
            SimulatorInfo("stepper", lambda: Stepper, "fixed steps", family="line"),
        ]


def test_any_comparing_family_is_benchmarked_with_its_own_columns(tmp_path: Path) -> None:
    registry = make_registry([LinePlugin()], entry_points=False)
    result = bench_simulators(5, 0, registry=registry)
    assert result.family == "line" and result.columns == ("past",)
    reference, stepper = result.rows
    assert (reference.name, reference.reference, reference.max_error) == ("exact", True, 0.0)
    # horizons 1..5 at dt 0.3 fall short by 0.1, 0.2, 0.0, 0.1, 0.2 s at speed 1
    assert stepper.max_error == pytest.approx(0.2) and stepper.median_error == pytest.approx(0.1)
    assert stepper.counts == {"past": 1.0}  # scene 0 ends at +0.05; the stepper leaves it at -0.05
    doc = tmp_path / "benchmarks.md"
    sim_report.update_section(doc, sim_report.markdown(result, None))
    text = doc.read_text()
    assert "| stepper:dt=0.3 |" in text and "| past |" in text and "points moving" in text


def test_a_non_finite_error_is_a_failed_scene_not_a_figure() -> None:
    class NanOnce(Exact):
        name = "nan-once"

        def run(self, scene: Mover, horizon: float | None = None) -> float:
            return math.nan if scene.scene_id == "s2" else super().run(scene, horizon)

    class NanPlugin(LinePlugin):
        @hookimpl
        def bpb_simulators(self) -> list[SimulatorInfo]:
            return [
                SimulatorInfo("exact", lambda: Exact, "closed form", family="line"),
                SimulatorInfo("nan-once", lambda: NanOnce, "nan on s2", family="line"),
            ]

    registry = make_registry([NanPlugin()], entry_points=False)
    _, row = bench_simulators(5, 0, ("nan-once",), registry=registry).rows
    # max() of a list holding nan depends on where the nan is; the scene is failed instead
    assert (row.failed, row.max_error, row.median_error) == (1, 0.0, 0.0)
    assert row.first_error == "error nan"


def test_scaling_does_not_time_a_simulator_s_first_load_as_a_scene() -> None:
    """A simulator's first run loads its imports or compiled code; --scaling, like the main
    comparison, runs each simulator once untimed, so the x1 figure is the scenes' cost."""

    class Cold(Exact):
        name = "cold"
        loaded = False

        def run(self, scene: Mover, horizon: float | None = None) -> float:
            if not Cold.loaded:  # what a first import or a compiled cache costs
                time.sleep(0.2)
                Cold.loaded = True
            return super().run(scene, horizon)

    class Counting(Line):
        def events(self, outcome: float) -> int:
            return 1

        def scaled_scene(self, scene: Mover, factor: float) -> Mover:
            return Mover(scene.scene_id, scene.horizon, scene.x, scene.v * factor)

    class ColdPlugin:
        @hookimpl
        def bpb_scene_families(self) -> list[SceneFamilyInfo]:
            return [SceneFamilyInfo("line", lambda: Counting, "points", default=True)]

        @hookimpl
        def bpb_simulators(self) -> list[SimulatorInfo]:
            return [
                SimulatorInfo("exact", lambda: Exact, "closed form", family="line"),
                SimulatorInfo("cold", lambda: Cold, "slow first run", family="line"),
            ]

    registry = make_registry([ColdPlugin()], entry_points=False)
    result = bench_simulators(2, 0, ("exact",), registry=registry)
    rows = with_scaling(result, ["cold"], 2, (1.0, 2.0), registry=registry).scaling
    assert [(r.factor, r.failed) for r in rows] == [(1.0, 0), (2.0, 0)]
    assert all(r.ms_per_scene is not None and r.ms_per_scene < 50 for r in rows), rows


def test_a_family_that_cannot_compare_is_bad_input() -> None:
    class Plain:
        name = "plain"

    class PlainPlugin:
        @hookimpl
        def bpb_scene_families(self) -> list[SceneFamilyInfo]:
            return [SceneFamilyInfo("plain", lambda: Plain, "no comparison")]

    registry = make_registry([PlainPlugin()], entry_points=False)
    with pytest.raises(BadInput, match="plain scene family cannot compare simulators"):
        bench_simulators(2, registry=registry)


def test_markdown_section_is_replaced_not_duplicated(tmp_path: Path, registry: Registry) -> None:
    result = bench_simulators(2, 1, ("analytic",), registry=registry)
    doc = tmp_path / "benchmarks.md"
    doc.write_text(f"# Benchmarks\n\n{sim_report.HEADING}\n\nold\n\n## Runner\n\nkeep me\n")
    sim_report.update_section(doc, sim_report.markdown(result))
    sim_report.update_section(doc, sim_report.markdown(result))
    text = doc.read_text()
    assert text.count(sim_report.HEADING) == 1 and "keep me" in text and "old" not in text
    assert "| analytic |" in text and "| analytic:precision=50 (reference) |" in text
    assert result.machine in text and text.index(sim_report.HEADING) < text.index("## Runner")


def test_notes_below_the_generated_part_survive_a_rerun(tmp_path: Path, registry: Registry) -> None:
    """What a maintainer writes under the generated tables (how the run was made, its reading)
    is kept when the section is regenerated; a section from before the end line is replaced
    whole, and the next section is untouched either way."""
    result = bench_simulators(2, 1, ("analytic",), registry=registry)
    doc = tmp_path / "benchmarks.md"
    doc.write_text(f"# Benchmarks\n\n{sim_report.HEADING}\n\nold table\n\n## Runner\n\nkeep me\n")
    sim_report.update_section(doc, sim_report.markdown(result))
    text = doc.read_text()
    assert "old table" not in text and text.count(sim_report.END) == 1
    notes = "Command: `bpb bench sim ...`, run on a quiet machine.\n"
    doc.write_text(text.replace(sim_report.END + "\n", sim_report.END + "\n\n" + notes))
    sim_report.update_section(doc, sim_report.markdown(result))
    sim_report.update_section(doc, sim_report.markdown(result))
    text = doc.read_text()
    assert text.count(notes) == 1 and text.count(sim_report.HEADING) == 1
    assert text.index(sim_report.END) < text.index(notes) < text.index("## Runner")
    assert text.endswith("## Runner\n\nkeep me\n")


def test_a_reader_never_sees_benchmarks_md_half_written(tmp_path: Path, registry: Registry) -> None:

    doc = tmp_path / "benchmarks.md"
    section = sim_report.markdown(bench_simulators(1, 0, ("analytic",), registry=registry), None)
    doc.write_text("# Benchmarks\n\n" + section + "\nkeep me\n\n## Runner\n\nkeep me too\n")
    writer = subprocess.Popen(  # another bench updating the same file, over and over
        [sys.executable, "-c", "import sys; from pathlib import Path\n"
         "from bpb_core.bench.sim_report import update_section\n"
         "for _ in range(400): update_section(Path(sys.argv[1]), sys.argv[2])",
         str(doc), section]
    )  # fmt: skip
    try:
        while writer.poll() is None:
            assert doc.read_text().endswith("keep me\n\n## Runner\n\nkeep me too\n")
    finally:
        writer.wait()
    assert writer.returncode == 0 and doc.read_text().count(sim_report.HEADING) == 1


def test_bench_sim_command_writes_table_plot_and_docs(
    tmp_path: Path, bench: Callable[..., Any]
) -> None:
    plot, doc = tmp_path / "img" / "bench_sim.png", tmp_path / "benchmarks.md"
    done = bench(
        "sim", "--scenes", "2", "--simulate-scenes", "20",
        "--contestant", "analytic", "--contestant", "pymunk:dt=0.01",
        "--plot", plot, "--markdown", doc,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert [row[0] for row in done.rows] == [
        "analytic:precision=50 (reference)",
        "analytic",
        "pymunk:dt=0.01",
    ]
    ms, max_error, median_error, *counts = done.row("pymunk:dt=0.01")
    assert float(ms) > 0 and float(max_error) >= float(median_error) > 0 and len(counts) == 4
    assert "bpb simulate (analytic), 1 worker, wall:" in done.stdout
    with Image.open(plot) as image:
        assert image.size[0] >= 1000
    text = doc.read_text()
    assert "![speed against error](img/bench_sim.png)" in text
    assert "| pymunk:dt=0.01 |" in text and "`bpb simulate` with `analytic` over 20" in text


def test_bench_sim_refuses_outputs_it_cannot_write_before_simulating(
    tmp_path: Path, bench: Callable[..., Any]
) -> None:
    folder, in_the_way = tmp_path / "img", tmp_path / "notes.txt"
    folder.mkdir()
    in_the_way.write_text("a file")
    latin1 = tmp_path / "benchmarks.md"
    latin1.write_bytes(b"# Benchmarks\n\ncaf\xe9\n")
    cases = [
        (("--plot", folder), f"error: {folder}: --plot: a folder"),
        (("--plot", in_the_way / "bench.png"), f"error: {in_the_way}: --plot: not a folder"),
        (("--markdown", folder), f"error: {folder}: --markdown: a folder"),
        (("--markdown", latin1), f"error: {latin1}: --markdown: not a readable UTF-8"),
    ]
    for option, message in cases:
        done = bench("sim", "--scenes", "1", "--simulate-scenes", "0", "--contestant",
                     "analytic", *option)  # fmt: skip
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1, done.stderr
        assert lines[0].startswith(message) and done.stdout == ""  # refused before the bench
    assert latin1.read_bytes() == b"# Benchmarks\n\ncaf\xe9\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["benchmarks.md", "img", "notes.txt"]


DIVERGING = """
from bpb_core.hookspecs import hookimpl
from bpb_core.registry import SimulatorInfo


class Diverging:
    name = "diverging"

    def run(self, scene, horizon=None):
        raise FloatingPointError("step size underflow")


@hookimpl
def bpb_simulators():
    return [SimulatorInfo("diverging", lambda: Diverging, "always fails", family="billiards")]
"""


def test_a_contestant_that_fails_on_every_scene_shows_no_figures(
    tmp_path: Path, bench: Callable[..., Any], monkeypatch: pytest.MonkeyPatch
) -> None:

    from support.plugin_dist import install_fake_dist

    site = tmp_path / "site"
    install_fake_dist(site, "bpb-diverging", "1.0", {"bpb_diverging": DIVERGING},
                      {"diverging": "bpb_diverging"})  # fmt: skip
    monkeypatch.syspath_prepend(str(site))  # installed: its entry point is found
    plot, doc = tmp_path / "sim.png", tmp_path / "benchmarks.md"
    args = ["sim", "--scenes", "3", "--simulate-scenes", "0", "--contestant", "analytic"]
    args += ["--contestant", "diverging", "--plot", plot, "--markdown", doc]
    done = bench(*args)
    assert done.returncode == 1, done.stderr
    assert done.row("diverging") == ["–", "–", "–", "–", "–", "–", "–", "3"]
    assert done.row("analytic")[-1] == "0" and float(done.row("analytic")[0]) > 0
    said = " ".join(done.stderr.split())
    assert "warning: diverging: failed on 3 scene(s)" in said and "step size underflow" in said
    text = doc.read_text()
    assert "| diverging | – | – | – | – | – | – | – | – | – | 3 |" in text
    assert "`diverging`" not in text.split("Reading:")[1]  # nothing read from its figures
    assert plot.stat().st_size > 0


def test_scaling_counts_a_simulator_s_refused_scenes_per_factor_and_keeps_the_rest(
    tmp_path: Path, bench: Callable[..., Any]
) -> None:
    # pymunk at its default 1e-3 s step refuses a scene made over 14.3 m/s: that ended the whole
    # benchmark with a bare "error: --dt: ..." (exit 3), every figure lost
    doc = tmp_path / "benchmarks.md"
    done = bench(
        "sim", "--scenes", "1", "--simulate-scenes", "0", "--contestant", "analytic",
        "--scaling", "pymunk", "--scaling", "analytic", "--scaling-scenes", "2",
        "--markdown", doc,
    )  # fmt: skip
    assert done.returncode == 1 and "Traceback" not in done.stderr, done.stderr
    assert [row[0] for row in done.rows] == ["analytic:precision=50 (reference)", "analytic"]
    lines = {line.split(":")[0]: line for line in done.stdout.splitlines() if line[:1] == "x"}
    assert [f for f in lines if f.endswith(" pymunk") and "failed" in lines[f]] == [
        "x16 pymunk",
        "x32 pymunk",
    ]
    assert lines["x16 pymunk"].endswith("µs/event, failed on 1 scene(s)")
    assert lines["x32 pymunk"] == (
        "x32 pymunk: – events/scene, – ms/scene, – µs/event, failed on 2 scene(s)"
    )
    analytic = [lines[f"x{f} analytic"] for f in (1, 2, 4, 8, 16, 32)]
    assert all("–" not in line and "failed" not in line for line in analytic)
    said = " ".join(done.stderr.split())
    assert said.count("warning:") == 1 and "failed" not in done.stdout.split("x1 ")[0]
    assert said.startswith("warning: --scaling pymunk: failed on 3 scaled scene(s) (x16: 1, ")
    assert "x32: 2), left out of its figures; first: SimulationError: dt: 0.001 s" in said
    text = doc.read_text()
    assert "| pymunk ms/scene | analytic ms/scene |" in text and "| pymunk failed scenes |" in text
    assert "| 8 |" in text and " | 0 |\n| 16 |" in text and " | – | " in text


def test_an_unknown_family_lists_the_known_scene_families(bench: Callable[..., Any]) -> None:
    done = bench("sim", "--scenes", "1", "--family", "snooker")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0].startswith("error: unknown scene family 'snooker'; known scene families: ")


def test_bench_sim_command_rejects_a_bad_contestant(bench: Callable[..., Any]) -> None:
    done = bench("sim", "--scenes", "1", "--contestant", "pymunk:dt")
    assert done.returncode == 2 and "--contestant 'pymunk:dt'" in done.stderr


@pytest.mark.parametrize(
    ("flag", "spec", "said"),
    [
        # the spec's option dt, not a --dt flag the command does not have
        ("--contestant", "pymunk:dt=-1", "dt: must be a positive finite number of seconds, got -1"),
        ("--contestant", "pymunk:tunnel=alow", "tunnel: must be refuse or allow, got 'alow'"),
        ("--reference", "pymunk:dt=-1", "dt: must be a positive finite number of seconds, got -1"),
        ("--simulate-with", "pymunk:tunnel=alow", "tunnel: must be refuse or allow, got 'alow'"),
    ],
)
def test_a_contestant_s_bad_option_value_names_the_flag_and_spec(
    bench: Callable[..., Any], flag: str, spec: str, said: str
) -> None:
    """The simulator's own refusal used to come alone ("error: --dt: must be ..."), naming no
    spec: with several contestants the user could not tell which one it was about."""
    args = ("sim", "--scenes", "100000", "--contestant", "analytic", "--simulate-scenes", "3")
    done = bench(*args, flag, spec)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [f"error: {flag} {spec!r}: {said}"]
    assert done.stdout == ""


@pytest.mark.parametrize(
    ("option", "message"),
    [
        (("--reference-scenes", "-2"), "--reference-scenes: must be at least 1, got -2"),
        (("--reference-scenes", "0"), "--reference-scenes: must be at least 1, got 0"),
        (("--reference", "analytic:precision"), "--reference 'analytic:precision': expected"),
        (("--scaling", "analytic", "--scaling-scenes", "0"), "--scaling-scenes: must be at"),
        (("--scaling", "nosuch"), "unknown simulator 'nosuch'"),
        (("--scaling", "pymunk:dt"), "--scaling 'pymunk:dt': expected name"),
        (("--simulate-scenes", "3", "--simulate-with", "nosuch"), "unknown simulator 'nosuch'"),
        (
            ("--simulate-scenes", "3", "--simulate-with", "pymunk:dt=-1"),
            "'pymunk:dt=-1': dt: must be",
        ),
        (("--simulate-scenes", "-1"), "--simulate-scenes: must be at least 0"),
    ],
)
def test_bench_sim_refuses_a_bad_option_of_any_step_before_simulating(
    bench: Callable[..., Any], option: tuple[str, ...], message: str
) -> None:
    # 100,000 scenes would take many minutes: refused at once, the comparison never ran
    args = ("sim", "--scenes", "100000", "--contestant", "analytic", "--simulate-scenes", "0")
    done = bench(*args, *option)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and message in lines[0], done.stderr
    assert done.stdout == ""


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


def test_parallel_simulate_lines_stop_at_a_bad_file_with_the_lines_before_it(
    tmp_path: Path,
) -> None:
    # a bad file in the first piece or in a later one ends the output with the lines before
    # it, then names the file
    paths, scenes = [], list(random_scenes(60, seed=9))
    for i, scene in enumerate(scenes):
        paths.append(tmp_path / f"s{i:02d}.json")
        paths[-1].write_text(scene.model_dump_json())
    good = list(simulate_lines(paths, workers=1))
    for bad in (3, 41):
        paths[bad].write_text("{")
        got: list[str] = []
        with pytest.raises(BadInput, match=f"s{bad:02d}.json"):
            for line in simulate_lines(paths, workers=2):
                got.append(line)
        assert got == good[:bad]
        paths[bad].write_text(scenes[bad].model_dump_json())


def test_the_speed_chart_draws_dollar_names_as_written(tmp_path: Path) -> None:
    """Simulator specs and family names are the user's and the plugins' text: ``$`` in them
    is no TeX formula (an invalid one stopped ``bpb bench sim`` at the plot)."""
    row = {"ms_per_scene": 2.0, "max_error": 1e-6, "median_error": 1e-9, "counts": {}}
    rows = [
        SimRow("exact", **(row | {"max_error": 0.0}), reference=True),
        SimRow("sim:mode=$\\frac{$", **row),
        SimRow("other $x$", **(row | {"ms_per_scene": 20.0})),
    ]
    result = SimBench("fam $y$", 2, 0, "", "", (), rows)
    sim_report.plot(result, tmp_path / "bench.png")
    with Image.open(tmp_path / "bench.png") as image:
        assert image.format == "PNG" and image.size[0] >= 1000
