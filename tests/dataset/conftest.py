"""Fixtures of the dataset tests: small real datasets generated once per session."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from bpb_core.dataset import generate_dataset
from bpb_core.registry import PluginWarning

warnings.filterwarnings("ignore", category=PluginWarning)

SMALL = {"per_horizon": 3, "horizons": [1.0, 3.0], "seed": 11}


@pytest.fixture(scope="session")
def small_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """6 scenes with images, generated on 2 worker processes."""
    out = tmp_path_factory.mktemp("small") / "ds"
    return generate_dataset(out, **SMALL, workers=2)  # type: ignore[arg-type]
