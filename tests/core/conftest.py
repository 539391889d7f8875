"""Fixtures that install throw-away plugin distributions for real.

A distribution here is what pip leaves behind: a package folder and a ``*.dist-info`` folder with
``METADATA`` and ``entry_points.txt`` on a ``sys.path`` entry. ``importlib.metadata`` finds it
exactly as it finds a pip-installed plugin, so discovery is tested end to end without network.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from collections.abc import Callable
from pathlib import Path

import pytest

BPB = str(Path(sys.executable).with_name("bpb"))


def install_fake_dist(
    site: Path, dist: str, version: str, modules: dict[str, str], entry_points: dict[str, str]
) -> None:
    """Write modules and a dist-info folder for ``dist`` into ``site``."""
    site.mkdir(parents=True, exist_ok=True)
    for name, source in modules.items():
        (site / f"{name}.py").write_text(textwrap.dedent(source))
    info = site / f"{dist.replace('-', '_')}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n")
    lines = "\n".join(f"{name} = {target}" for name, target in entry_points.items())
    (info / "entry_points.txt").write_text(f"[bpb]\n{lines}\n")


InstallFn = Callable[[str, str, dict[str, str], dict[str, str]], None]


@pytest.fixture
def site(tmp_path: Path) -> Path:
    """An empty site directory that :func:`run_bpb` puts on ``PYTHONPATH``."""
    return tmp_path / "site"


@pytest.fixture
def install(site: Path) -> InstallFn:
    """Install a fake distribution into ``site``."""

    def _install(dist: str, version: str, modules: dict[str, str], eps: dict[str, str]) -> None:
        install_fake_dist(site, dist, version, modules, eps)

    return _install


@pytest.fixture
def run_bpb(site: Path) -> Callable[..., subprocess.CompletedProcess[str]]:
    """Run the real ``bpb`` console script with ``site`` on its path."""

    def _run(*args: str) -> subprocess.CompletedProcess[str]:
        env = {**os.environ, "PYTHONPATH": str(site)}
        return subprocess.run([BPB, *args], capture_output=True, text=True, env=env, timeout=120)

    return _run
