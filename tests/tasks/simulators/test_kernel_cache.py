"""The compiled kernel's on-disk cache follows edits to any compiled module, not only the
function's own file (numba alone would keep a caller's cached code after its callee changed)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("numba")

CALLEE = """from bpb_tasks.simulators.analytic.kernel_roots import jit


@jit
def step():
    return {value}
"""

CALLER = """from bpb_tasks.simulators.analytic.kernel_roots import jit
from callee import step


@jit
def total():
    return step() + 10
"""


def _total(folder: Path) -> str:
    path = os.pathsep.join(filter(None, [str(folder), os.environ.get("PYTHONPATH")]))
    done = subprocess.run(
        [sys.executable, "-c", "import caller; print(caller.total())"],
        cwd=folder,
        env={**os.environ, "PYTHONPATH": path},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def test_a_callers_cached_code_follows_an_edit_of_its_callee_s_file(tmp_path: Path) -> None:
    (tmp_path / "callee.py").write_text(CALLEE.format(value=1))
    (tmp_path / "caller.py").write_text(CALLER)
    assert _total(tmp_path) == "11"
    (index,) = (tmp_path / "__pycache__").glob("caller.total-*.nbi")
    written = index.stat().st_mtime_ns
    assert _total(tmp_path) == "11"
    assert index.stat().st_mtime_ns == written  # nothing changed: loaded from the cache
    (tmp_path / "callee.py").write_text(CALLEE.format(value=2))  # caller.py untouched
    assert _total(tmp_path) == "12"
