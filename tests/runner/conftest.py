"""Fixtures of the runner tests: a small dataset with analytic ground truth."""

from __future__ import annotations

from pathlib import Path

import pytest
from runner_scenes import make_dataset


@pytest.fixture(scope="session")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two horizons x three scenes: init.json, final.json (analytic) and a small init.png."""
    return make_dataset(tmp_path_factory.mktemp("runner") / "data")


@pytest.fixture
def secret_key(monkeypatch: pytest.MonkeyPatch) -> str:
    """An OpenAI key in the environment that must never reach a file."""
    key = "sk-bpbtest-0123456789abcdefSECRET"
    monkeypatch.setenv("OPENAI_API_KEY", key)
    return key
