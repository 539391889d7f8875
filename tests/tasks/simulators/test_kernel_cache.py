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


NOTE = "compiling the physics kernel for this machine"


def _generate(out: Path, cache: Path) -> subprocess.CompletedProcess[str]:
    bpb = str(Path(sys.executable).with_name("bpb"))
    args = ["generate", "--out", str(out), "--per-horizon", "2", "--horizons", "1",
            "--workers", "2", "--stable-only", "--no-images"]  # fmt: skip
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    return subprocess.run([bpb, *args], capture_output=True, text=True, env=env, timeout=600)


def test_bpb_says_once_that_it_compiles_the_kernel_and_nothing_once_it_is_cached(
    tmp_path: Path,
) -> None:
    """A first command on a machine compiles for about 20 s: one line on stderr says so, not
    one per worker (--stable-only starts its pool before any scene is made; the first one is
    made, and the code built, in the parent). The next command loads the cache silently."""
    cache = tmp_path / "numba-cache"
    cache.mkdir()
    cold = _generate(tmp_path / "cold", cache)
    assert cold.returncode == 0, cold.stderr
    (line,) = [line for line in cold.stderr.splitlines() if NOTE in line]
    assert line.startswith("note: ") and line.endswith(f"cached in {cache} for later commands")
    warm = _generate(tmp_path / "warm", cache)
    assert warm.returncode == 0, warm.stderr
    assert warm.stderr == ""
    # bpb simulate's fast path is code generation never ran: built on its first use, said again
    # (the note said "once", then came back); then loaded silently
    bpb = str(Path(sys.executable).with_name("bpb"))
    simulate = [bpb, "simulate", str(tmp_path / "cold"), "--engine", "kernel", "--workers", "1"]
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    lines = []
    for _ in range(2):
        done = subprocess.run(simulate, capture_output=True, text=True, env=env, timeout=600)
        assert done.returncode == 0, done.stderr
        lines.append(done.stderr)
    assert lines == [f"note: {NOTE} (about 20 s); cached in {cache} for later commands\n", ""]
    assert line == lines[0].rstrip("\n")


SPAWNED_BPB = """import multiprocessing, sys
multiprocessing.set_start_method("spawn")
from bpb_core.cli.main import main
main(sys.argv[1:])
"""


def test_workers_that_are_not_forked_load_the_kernel_the_parent_built(tmp_path: Path) -> None:
    """macOS starts a pool's workers with spawn, Linux from Python 3.14 with forkserver: they
    inherit nothing from bpb. On a cold cache each worker built the kernel itself (twice the
    CPU on 2 workers) and gave the note as a raw Python warning, with the file and line of
    bpb's code. The parent builds it first there too; the workers load it from numba's cache."""
    cache = tmp_path / "numba-cache"
    cache.mkdir()
    args = ["generate", "--out", str(tmp_path / "ds"), "--per-horizon", "2", "--horizons", "1",
            "--workers", "2", "--no-images"]  # fmt: skip
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    done = subprocess.run([sys.executable, "-c", SPAWNED_BPB, *args], capture_output=True,
                          text=True, env=env, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stderr == f"note: {NOTE} (about 20 s); cached in {cache} for later commands\n"


def test_the_note_names_where_numba_caches_all_of_it_without_numba_cache_dir(
    tmp_path: Path,
) -> None:
    """Without NUMBA_CACHE_DIR numba caches each compiled module's code in the ``__pycache__``
    beside it: the stability code's and the kernel's in two folders. The note named the first
    one to compile only (``.../billiards/__pycache__``), half of what was built."""
    import shutil

    import bpb_tasks

    copy = tmp_path / "bpb_tasks"  # sources numba has never seen: a cold cache beside them
    shutil.copytree(
        Path(bpb_tasks.__file__).parent, copy, ignore=shutil.ignore_patterns("__pycache__")
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(tmp_path), env.get("PYTHONPATH")]))
    args = ["generate", "--out", str(tmp_path / "ds"), "--per-horizon", "1", "--horizons", "1",
            "--workers", "1", "--no-images"]  # fmt: skip
    bpb = str(Path(sys.executable).with_name("bpb"))
    done = subprocess.run([bpb, *args], capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr
    where = f"the __pycache__ folders under {copy}"
    assert done.stderr == f"note: {NOTE} (about 20 s); cached in {where} for later commands\n"
    for folder in ("billiards", "simulators/analytic"):
        assert list((copy / folder / "__pycache__").glob("*.nbi")), folder
