"""The result of ``bpb bench sim`` (:class:`SimBench`) and its figures: the markdown section
of docs/benchmarks.md and the PNG plot.

Both are built from a :class:`SimBench` alone; the column names, the description of the scenes
and the meaning of the measures are the scene family's.
"""

from __future__ import annotations

import math
import os
import platform
import textwrap
from dataclasses import dataclass, field
from datetime import date
from pathlib import Path

from bpb_core.run_folder import write_bytes_atomic

HEADING = "## Simulation speed against error (`bpb bench sim`)"
END = "<!-- end of the bpb bench sim output: what follows in this section is kept -->"
WIDTH = 100


def machine_description() -> str:
    """``2 cores, <CPU model>, CPython 3.11.7``: the machine a figure was measured on."""
    model = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    python = f"{platform.python_implementation()} {platform.python_version()}"
    return f"{os.cpu_count()} cores, {model}, {python}"


@dataclass(frozen=True)
class SimRow:
    """One contestant's figures over the benchmark scenes (``counts`` in column order; errors
    and counts over the scenes the reference ran; ``us_per_event`` when the family counts
    events, ``batch_ms`` per scene of the simulator's batch call when it has one).

    A scene on which the contestant raised, or whose comparison gave a non-finite error, is
    ``failed`` (``first_error`` says why) and counts in no figure: with every scene failed,
    the time is None, and with none compared the errors are None and ``counts`` is empty."""

    name: str
    ms_per_scene: float | None
    max_error: float | None
    median_error: float | None
    counts: dict[str, float]
    reference: bool = False
    us_per_event: float | None = None
    batch_ms: float | None = None
    failed: int = 0
    first_error: str = ""


@dataclass(frozen=True)
class SimBench:
    """The result of :func:`bench_simulators` (``rows``: the reference first)."""

    family: str
    scenes: int
    seed: int
    description: str
    measures: str
    columns: tuple[str, ...]
    rows: list[SimRow]
    simulate_ms: dict[str, float] | None = None
    simulate_scenes: int = 0
    simulate_with: str = ""
    compared: int = 0
    scaling: list[ScaleRow] = field(default_factory=list)
    machine: str = field(default_factory=machine_description)
    day: str = field(default_factory=lambda: date.today().isoformat())  # 2026-11-21


@dataclass(frozen=True)
class ScaleRow:
    """Cost of one contestant on the scenes made busier by ``factor``: means over the scenes
    it ran. A scene on which it raised is ``failed`` (``first_error`` says why) and counts in
    neither mean; with every scene failed both are None."""

    factor: float
    name: str
    ms_per_scene: float | None
    events_per_scene: float | None
    failed: int = 0
    first_error: str = ""

    @property
    def us_per_event(self) -> float | None:
        """Microseconds per event (None when every scene failed)."""
        if self.ms_per_scene is None or self.events_per_scene is None:
            return None
        return 1000 * self.ms_per_scene / self.events_per_scene if self.events_per_scene else 0.0


def count_text(value: float) -> str:
    """A summed disagreement count: ``3`` when whole, else three significant digits."""
    return str(int(value)) if float(value).is_integer() else f"{value:.3g}"


def count_cell(row: SimRow, column: str) -> str:
    """``row``'s summed count of ``column``, or "–" when it compared no scene."""
    return count_text(row.counts[column]) if column in row.counts else "–"


def figure(value: float | None, spec: str = ".3g") -> str:
    """A figure in ``spec``, or "–" where there is none (every scene failed)."""
    return "–" if value is None else format(value, spec)


def row_name(row: SimRow) -> str:
    """The contestant's spec, marked when it is the reference."""
    return f"{row.name} (reference)" if row.reference else row.name


def markdown(result: SimBench, plot: str | None = "img/bench_sim.png") -> str:
    """The benchmark section (heading included), with machine and date."""
    reference = next((r.name for r in result.rows if r.reference), "?")
    intro = (
        f"{result.scenes} {result.description} (scene family `{result.family}`, seed "
        f"{result.seed}); every simulator runs every scene in turn (runs under 5 ms repeated up "
        "to 5 times, the quickest counted; ms/scene is the mean over scenes). Each outcome is "
        f"compared with the reference `{reference}`: {result.measures}. Max and median of the "
        "error over scenes; the other columns are summed over scenes."
    )
    lines = [HEADING, "", f"{result.day}, {result.machine}.", "", _wrap(intro), ""]
    if result.compared and result.compared < result.scenes:
        lines += [
            _wrap(
                f"The reference ran on the first {result.compared} scenes only: errors and "
                f"disagreements are over those {result.compared}, times over all "
                f"{result.scenes}."
            ),
            "",
        ]
    lines += _table(result)
    if result.scaling:
        lines += ["", *_scaling(result)]
    reading = _reading(result)
    if reading:
        lines += ["", _wrap(reading)]
    if result.simulate_ms is not None:
        figures = ", ".join(f"{k}: **{ms:.3f} ms/scene**" for k, ms in result.simulate_ms.items())
        simulate = (
            f"`bpb simulate` with `{result.simulate_with}` over {result.simulate_scenes} scene "
            "files (read, validate, simulate, build and serialise the ground truth; start-up "
            f"excluded; best of 3 interleaved rounds): {figures}."
        )
        lines += ["", _wrap(simulate)]
    if plot:
        lines += ["", f"![speed against error]({plot})"]
    lines += ["", END]
    return "\n".join(lines) + "\n"


def _wrap(text: str) -> str:
    return textwrap.fill(text, WIDTH, break_on_hyphens=False)


def _table(result: SimBench) -> list[str]:
    per_event = any(r.us_per_event is not None for r in result.rows)
    batch = any(r.batch_ms is not None for r in result.rows)
    head = ["simulator", "ms/scene"]
    head += ["µs/event"] * per_event + ["batch ms/scene"] * batch
    failed = any(r.failed for r in result.rows)
    head += ["max error", "median error", *result.columns] + ["failed scenes"] * failed
    lines = ["| " + " | ".join(head) + " |", "| --- |" + " ---: |" * (len(head) - 1)]
    for row in result.rows:
        cells = [row_name(row), figure(row.ms_per_scene)]
        cells += [figure(row.us_per_event)] * per_event + [figure(row.batch_ms)] * batch
        cells += [figure(row.max_error, ".2e"), figure(row.median_error, ".2e")]
        cells += [count_cell(row, c) for c in result.columns] + [str(row.failed)] * failed
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _scaling(result: SimBench) -> list[str]:
    """Cost against events per scene (the scaled scenes of ``--scaling``)."""
    names = list(dict.fromkeys(r.name for r in result.scaling))
    failing = list(dict.fromkeys(r.name for r in result.scaling if r.failed))
    head = ["speed x", "events/scene", *(f"{n} ms/scene" for n in names)]
    head += [f"{n} µs/event" for n in names] + [f"{n} failed scenes" for n in failing]
    lines = [
        _wrap(
            "Cost against events per scene: the same scenes made busier by the family (same "
            "simulated time, more events)."
        ),
        "",
        "| " + " | ".join(head) + " |",
        "| ---: |" + " ---: |" * (len(head) - 1),
    ]
    for factor in dict.fromkeys(r.factor for r in result.scaling):
        rows = {r.name: r for r in result.scaling if r.factor == factor}
        events = (rows[n].events_per_scene for n in names)  # the first simulator that ran
        cells = [f"{factor:g}", figure(next((e for e in events if e is not None), None))]
        cells += [figure(rows[n].ms_per_scene) for n in names]
        cells += [figure(rows[n].us_per_event) for n in names]
        cells += [str(rows[n].failed) for n in failing]
        lines.append("| " + " | ".join(cells) + " |")
    if failing:
        first = next(r for r in result.scaling if r.failed)
        lines += [
            "",
            _wrap(
                "Failed scenes: the simulator raised on the scaled scene, which is left out of "
                'its means ("–" where every scene failed; events/scene is then the next '
                "simulator's); first: "
                f"`{first.name}` at x{first.factor:g}, {first.first_error}"
            ),
        ]
    return lines


def _reading(result: SimBench) -> str:
    """Plain-language reading of the table, computed from it."""
    reference = next((r for r in result.rows if r.reference), None)
    others = sorted(
        # every scene ran and was compared: rows the reading may rank
        (r for r in result.rows if not (r.reference or r.failed or r.max_error is None)),
        key=lambda r: (_num(r.max_error), _num(r.ms_per_scene)),
    )
    if reference is None or reference.ms_per_scene is None or not others:
        return ""
    best = others[0]
    text = (
        f"Reading: `{best.name}` comes closest to the reference (max error "
        f"{best.max_error:.1e}, {count_text(sum(best.counts.values()))} disagreements in all) at "
        f"{best.ms_per_scene:.3g} ms per scene, "
        f"{_speed(_num(best.ms_per_scene), reference.ms_per_scene)} the reference."
    )
    if len(others) > 1:
        runner = min(others[1:], key=lambda r: (_num(r.median_error), _num(r.ms_per_scene)))
        text += (
            f" The most accurate of the others, `{runner.name}`, is "
            f"{_speed(_num(runner.ms_per_scene), _num(best.ms_per_scene))} `{best.name}`, "
            f"with median error {runner.median_error:.1e}, max error {runner.max_error:.1e} "
            f"and {count_text(sum(runner.counts.values()))} disagreements."
        )
    return text


def _num(value: float | None) -> float:
    return math.inf if value is None else value


def _speed(ms: float, other_ms: float) -> str:
    """``22.5x faster than`` or ``3.1x slower than``."""
    if ms <= 0 or other_ms <= 0:
        return "not comparable in speed with"
    ratio = max(ms, other_ms) / min(ms, other_ms)
    times = f"{ratio:,.0f}x" if ratio >= 100 else f"{ratio:.3g}x"
    return f"{times} faster than" if ms <= other_ms else f"{times} slower than"


def check_section_file(path: Path) -> None:
    """Check before the benchmark that :func:`update_section` can read and write ``path``.

    Raises:
        BadInput: ``path`` is a folder, unwritable, or a file that is not UTF-8 text.
    """
    from bpb_core.errors import BadInput
    from bpb_core.layout import check_writable_file

    check_writable_file(path, "--markdown")
    if path.exists():
        try:
            path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise BadInput(f"{path}: --markdown: not a readable UTF-8 text file ({exc})") from None


def update_section(path: Path, section: str) -> None:
    """Replace the generated part of the section starting with :data:`HEADING` in ``path`` (or
    append the section). The generated part ends with the :data:`END` line; notes written below
    it, up to the next ``## `` heading, are kept. A section without that line (written before it
    existed) is replaced whole."""
    text = path.read_text(encoding="utf-8") if path.exists() else "# Benchmarks\n"
    start = text.find(HEADING)
    if start < 0:
        text = text.rstrip("\n") + "\n\n" + section
    else:
        end = text.find("\n## ", start + len(HEADING))
        marker = text.find(END, start, len(text) if end < 0 else end)
        if marker >= 0:
            rest = text[marker + len(END) :].lstrip("\n")
        else:
            rest = "" if end < 0 else text[end + 1 :]
        text = text[:start] + section + ("\n" + rest if rest else "")
    write_bytes_atomic(path, text.encode("utf-8"))  # a reader never sees the file half-written


def plot(result: SimBench, path: Path) -> None:
    """Speed against error, log-log: one point per contestant (max error, with the median);
    the reference (error 0 by definition) is left out. Drawn by :mod:`bpb_core.report.charts`:
    names as written, the process's matplotlib left alone."""
    from bpb_core.report.charts import figure, png

    floor = 1e-17
    fig, axes = figure(1, 1, (8, 5), dpi=150)
    ax = axes[0, 0]
    for row in (r for r in result.rows if not r.reference):
        if row.ms_per_scene is None or row.max_error is None or row.median_error is None:
            continue  # every scene failed or none compared: no point to draw
        x = row.ms_per_scene
        high, mid = max(row.max_error, floor), max(row.median_error, floor)
        ax.plot([x, x], [mid, high], color="0.6", lw=1)
        ax.scatter([x], [high], s=45, zorder=3, label=f"{row.name}: {x:.3g} ms, max {high:.1e}")
        ax.scatter([x], [mid], s=80, marker="_", color="k", zorder=3)
    ax.scatter([], [], s=80, marker="_", color="k", label="median error over scenes")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.margins(x=0.15, y=0.15)
    ax.set_xlabel("time per scene (ms, log scale)")
    ax.set_ylabel("error against the reference (log scale)")
    ax.set_title(f"{result.family} simulators: speed against error ({result.scenes} scenes)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="lower right", title="dot = max error over scenes", title_fontsize=7)
    write_bytes_atomic(path, png(fig))
