"""The per-horizon tally of the manifest and the ``stats/`` figure of a slider dataset."""

from __future__ import annotations

import io
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

BOUNCES_PNG = "stats/bounces.png"


@dataclass
class SliderTally:
    """Bounce counts of the kept scenes of one horizon."""

    bounces: list[int] = field(default_factory=list)

    def add(self, row: Mapping[str, object]) -> None:
        """Count one kept scene from its ``index.csv`` cells."""
        value = row["bounces"]
        assert isinstance(value, int)
        self.bounces.append(value)

    def summary(self) -> dict[str, Any]:
        """The share of scenes with a wall hit and the mean hit count."""
        n = len(self.bounces)
        hit = sum(1 for b in self.bounces if b > 0)
        return {
            "bounce_rate": round(hit / n, 6) if n else 0.0,
            "mean_bounces": round(sum(self.bounces) / n, 6) if n else 0.0,
        }


def bounce_figure(tallies: Mapping[float, SliderTally]) -> bytes:
    """Grouped bars: how many scenes of each horizon hit the walls 0, 1, 2, ... times."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    fig = Figure(figsize=(5.0, 3.0), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    top = max((max(t.bounces, default=0) for t in tallies.values()), default=0)
    width = 0.8 / max(len(tallies), 1)
    for i, (horizon, tally) in enumerate(sorted(tallies.items())):
        counts = [tally.bounces.count(k) for k in range(top + 1)]
        xs = [k + (i - (len(tallies) - 1) / 2) * width for k in range(top + 1)]
        ax.bar(xs, counts, width=width, label=f"{horizon:g} s")
    ax.set_xlabel("wall hits by the horizon")
    ax.set_ylabel("scenes")
    ax.set_xticks(range(top + 1))
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.legend(title="horizon")
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", metadata={"Software": None})
    return buffer.getvalue()


def write_stats(root: Path, tallies: Mapping[float, SliderTally]) -> list[str]:
    """Write :data:`BOUNCES_PNG` under ``root``; return its relative path."""
    (root / "stats").mkdir(exist_ok=True)
    (root / BOUNCES_PNG).write_bytes(bounce_figure(tallies))
    return [BOUNCES_PNG]
