"""Fixtures shared by every test folder.

Test helpers live in the ``support`` package (``tests/`` is on ``pythonpath``); only fixtures are
here, because conftest modules share one name across folders and are never imported.

- ``registry``: a fresh registry of the installed plugins, built per test (no process-global
  plugin state).
- ``site``, ``install``, ``run_bpb``: throw-away plugin distributions installed for real (a
  package folder and a ``*.dist-info`` with ``entry_points.txt`` on ``PYTHONPATH``), and the
  real ``bpb`` console script run with them.
- ``dataset``: two horizons x three scenes with analytic ground truth and a small ``init.png``.
- ``small_dataset``: 6 scenes with images made by ``generate_dataset`` on 2 workers.
- ``runs``: the oracle, stasis and model run folders of the hand-made report fixture.
- ``secret_key``: an OpenAI key in the environment that must never reach a file.
- ``compiled_code`` (every session): numba's cache of bpb's compiled code filled first, so that
  no ``bpb`` command of a test builds it and says so on stderr. The cache is one folder for the
  session (:func:`pytest_configure` sets ``NUMBA_CACHE_DIR``, which subprocesses inherit), under
  the temporary folder and keyed like bpb's own by the version and the compiled sources: a
  second run of the suite finds it warm, and an edit of the kernel starts a new one.
"""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import pytest

from bpb_core.registry import Registry, make_registry
from support.dataset_small import SMALL
from support.plugin_dist import InstallFn, install_fake_dist
from support.reports_fixture import write_runs
from support.runner_scenes import make_dataset

BPB = str(Path(sys.executable).with_name("bpb"))


def pytest_configure(config: pytest.Config) -> None:
    """One numba cache folder for the session, set before any test module imports the kernel
    (``NUMBA_CACHE_DIR`` in ``os.environ``: this process and every subprocess use it)."""
    from bpb_tasks.simulators.analytic.engine import cache_folder

    folder = Path(tempfile.gettempdir()) / f"bpb-tests-numba-{os.getuid()}" / cache_folder().name
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    # pytest-xdist's workers get COLUMNS=80 and LINES=24; a bpb command piped has neither
    for name in ("COLUMNS", "LINES"):
        os.environ.pop(name, None)


@pytest.fixture(scope="session", autouse=True)
def compiled_code() -> None:
    """numba's cache filled before any test (:mod:`support.compiled_code`), in a process of
    its own: this one keeps numba unloaded. pytest-xdist's workers take turns under a lock on
    the cache folder, so the first builds and the others load what it built."""
    folder = Path(os.environ["NUMBA_CACHE_DIR"])
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder.with_name(folder.name + ".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        done = subprocess.run(
            [sys.executable, "-m", "support.compiled_code"],
            cwd=Path(__file__).parent,
            capture_output=True,
            text=True,
            timeout=900,
        )
    assert done.returncode == 0, done.stderr


@pytest.fixture
def registry() -> Registry:
    """A fresh registry of the installed plugins."""
    return make_registry(warn=False)


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
    """Run the real ``bpb`` console script with ``site`` on its path (before ``PYTHONPATH``)."""

    def _run(*args: str) -> subprocess.CompletedProcess[str]:
        # site first; a PYTHONPATH already set (a git worktree's src) stays after it
        path = os.pathsep.join(filter(None, [str(site), os.environ.get("PYTHONPATH")]))
        env = {**os.environ, "PYTHONPATH": path}
        return subprocess.run([BPB, *args], capture_output=True, text=True, env=env, timeout=120)

    return _run


@pytest.fixture(scope="session")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two horizons x three scenes: init.json, final.json (analytic) and a small init.png."""
    return make_dataset(tmp_path_factory.mktemp("runner") / "data")


@pytest.fixture(scope="session")
def small_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """6 scenes with images, generated on 2 worker processes."""
    from bpb_core.dataset import generate_dataset

    out = tmp_path_factory.mktemp("small") / "ds"
    return generate_dataset(out, **SMALL, workers=2)  # type: ignore[arg-type]


@pytest.fixture
def runs(tmp_path: Path) -> Path:
    """``tmp_path/runs`` holding the oracle, stasis and model run folders."""
    return write_runs(tmp_path)


@pytest.fixture
def secret_key(monkeypatch: pytest.MonkeyPatch) -> str:
    """An OpenAI key in the environment that must never reach a file."""
    key = "sk-bpbtest-0123456789abcdefSECRET"
    monkeypatch.setenv("OPENAI_API_KEY", key)
    return key
