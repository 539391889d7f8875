"""Figures of ``bpb bench sim``: the markdown section of docs/benchmarks.md and the PNG plot."""

from __future__ import annotations

from pathlib import Path

from bpb_tasks.simulators.bench import SimBench

HEADING = "## Simulators (`bpb bench sim`)"


def markdown(result: SimBench, plot: str | None = "img/bench_sim.png") -> str:
    """The benchmark section (heading included), with machine and date."""
    lines = [
        HEADING,
        "",
        f"{result.day}, {result.machine}.",
        "",
        f"{result.scenes} random 7-ball scenes (seed {result.seed}, only the cue ball moving at",
        "0.1-1.2 m/s, horizons 1-5 s), every simulator run on every scene in turn (runs under",
        "5 ms repeated up to 5 times, the quickest counted; ms/scene is the mean over scenes).",
        "Error = final-position distance to the 50-digit mpmath run of `analytic`",
        "(per scene the worst ball; max and median over scenes). Disagreements = scenes whose",
        "Q1 contacts, Q2 walls or pocketed set differ from the reference; Q3 = balls the Q3",
        "scorer would mark wrong (more than R off, or pocketed in one run only).",
        "",
        "| simulator | ms/scene | max error (m) | median error (m) | Q1 | Q2 | pocketed | Q3 |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for row in result.rows:
        lines.append(
            f"| {row.name} | {row.ms_per_scene:.3g} | {row.max_error:.2e} | "
            f"{row.median_error:.2e} | {row.q1_disagree} | {row.q2_disagree} | "
            f"{row.pocket_disagree} | {row.q3_wrong} |"
        )
    lines += ["", *_reading(result)]
    if result.simulate_ms is not None:
        figures = ", ".join(
            f"{label}: **{ms:.3f} ms/scene**" for label, ms in result.simulate_ms.items()
        )
        lines += [
            "",
            f"`bpb simulate` over {result.simulate_scenes} scene files (read, validate, simulate,",
            "build and serialise final.json; start-up excluded; best of 3 interleaved rounds):",
            f"{figures}",
            "(target: at most 0.4 ms/scene).",
        ]
    if plot:
        lines += ["", f"![speed against error]({plot})"]
    return "\n".join(lines) + "\n"


def _reading(result: SimBench) -> list[str]:
    """Plain-language reading of the table, computed from it."""
    rows = {row.name: row for row in result.rows}
    exact = rows.get("analytic")
    engines = [row for name, row in rows.items() if name.startswith("pymunk")]
    if exact is None or not engines:
        return []
    best = min(engines, key=lambda row: row.median_error)
    flips = exact.q1_disagree + exact.q2_disagree + exact.pocket_disagree
    agree = "identical labels" if flips == 0 else f"{flips} label disagreements"
    return [
        f"Reading: `analytic` (float64) stays within {exact.max_error:.0e} m of the 50-digit",
        f"reference with {agree}, at {exact.ms_per_scene:.3g} ms per scene. The most",
        f"accurate fixed-step run ({best.name}) is {best.ms_per_scene / exact.ms_per_scene:.0f}x",
        f"slower, its median error ({best.median_error:.1e} m) shrinks only in proportion to dt,",
        "and its worst scenes are off by decimetres: a contact a few microseconds late sends",
        "a ball elsewhere, which is why the ground truth uses the exact simulator.",
    ]


def update_section(path: Path, section: str) -> None:
    """Replace the section starting with :data:`HEADING` in ``path`` (or append it)."""
    text = path.read_text() if path.exists() else "# Benchmarks\n"
    start = text.find(HEADING)
    if start < 0:
        text = text.rstrip("\n") + "\n\n" + section
    else:
        end = text.find("\n## ", start + len(HEADING))
        rest = "" if end < 0 else text[end + 1 :]
        text = text[:start] + section + ("\n" + rest if rest else "")
    path.write_text(text)


def plot(result: SimBench, path: Path) -> None:
    """Speed against error, log-log: one point per simulator (max error, with the median)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    floor = 1e-17
    fig, ax = plt.subplots(figsize=(8, 5), dpi=150)
    for row in result.rows:
        if "reference" in row.name:
            continue
        x = row.ms_per_scene
        high, mid = max(row.max_error, floor), max(row.median_error, floor)
        ax.plot([x, x], [mid, high], color="0.6", lw=1)
        ax.scatter([x], [high], s=45, zorder=3, label=f"{row.name}: {x:.3g} ms, max {high:.1e} m")
        ax.scatter([x], [mid], s=80, marker="_", color="k", zorder=3)
    ax.scatter([], [], s=80, marker="_", color="k", label="median error over scenes")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.margins(x=0.15, y=0.15)
    ax.set_xlabel("time per scene (ms, log scale)")
    ax.set_ylabel("final-position error vs mpmath reference (m, log)")
    ax.set_title(f"Simulators: speed against error ({result.scenes} scenes, {result.day})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="lower right", title="dot = max error over scenes", title_fontsize=7)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
