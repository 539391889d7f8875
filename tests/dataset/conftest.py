"""Fixtures of the dataset tests: small real datasets generated once per session."""

from __future__ import annotations

from pathlib import Path

import pytest
from dataset_small import SMALL

from bpb_core.dataset import generate_dataset


@pytest.fixture(scope="session")
def small_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """6 scenes with images, generated on 2 worker processes."""
    out = tmp_path_factory.mktemp("small") / "ds"
    return generate_dataset(out, **SMALL, workers=2)  # type: ignore[arg-type]
