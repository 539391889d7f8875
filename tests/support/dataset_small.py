"""The small dataset the dataset tests share (a plain module: conftest modules share one name
across test folders, so nothing is imported from them)."""

from __future__ import annotations

SMALL = {"per_horizon": 3, "horizons": [1.0, 3.0], "seed": 11}
