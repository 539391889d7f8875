"""The compiled kernel's on-disk cache follows edits to any compiled module, not only the
function's own file (numba alone would keep a caller's cached code after its callee changed);
building it is said in one note, and nothing is said once it is cached.

A cold build of all of it takes about 25 s on 2 cores: the tests of what ``bpb`` says share
one (:func:`cold`)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
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


def _run_total(folder: Path, env: dict[str, str]) -> tuple[str, str]:
    path = os.pathsep.join(filter(None, [str(folder), os.environ.get("PYTHONPATH")]))
    done = subprocess.run(
        [sys.executable, "-c", "import caller; print(caller.total())"],
        cwd=folder,
        env={**os.environ, "PYTHONPATH": path, **env},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.strip(), done.stderr


def _total(folder: Path) -> str:
    return _run_total(folder, {})[0]


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


LEAN_LOAD_FAILS = """import sys
from bpb_tasks.simulators.analytic import kernel_roots

cache_class = kernel_roots._stamped_cache_class()
lean = cache_class._load_overload
calls = []


def first_fails(self, sig, target_context):
    calls.append(sig)
    if len(calls) == 1:
        raise KeyError("a symbol only numba's refresh installs")
    return lean(self, sig, target_context)


cache_class._load_overload = first_fails
kernel_roots._stamped_cache_class = lambda: cache_class
import caller

print(caller.total(), len(calls))
"""


def test_cached_code_the_lean_load_cannot_link_is_loaded_numba_s_way(tmp_path: Path) -> None:
    # the cached kernels load without numba's refresh of its lowering code (0.25 s a process);
    # should another numba's code need it, that load failing falls back to numba's own
    (tmp_path / "callee.py").write_text(CALLEE.format(value=3))
    (tmp_path / "caller.py").write_text(CALLER)
    assert _total(tmp_path) == "13"  # compiled and cached
    (index,) = (tmp_path / "__pycache__").glob("caller.total-*.nbi")
    written = index.stat().st_mtime_ns
    path = os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")]))
    done = subprocess.run([sys.executable, "-c", LEAN_LOAD_FAILS], cwd=tmp_path,
                          env={**os.environ, "PYTHONPATH": path}, capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["13", "2"]  # the lean load, then numba's, which loaded it
    assert index.stat().st_mtime_ns == written and NOTE not in done.stderr  # not compiled


NOTE = "compiling the physics kernel for this machine"
BPB = str(Path(sys.executable).with_name("bpb"))
SPAWNED_BPB = """import multiprocessing, sys
multiprocessing.set_start_method("spawn")
from bpb_core.cli.main import main
main(sys.argv[1:])
"""


@dataclass(frozen=True)
class ColdBuild:
    """One ``bpb generate`` that built all of its compiled code: its stderr, the copy of
    ``bpb_tasks`` it ran (its ``__pycache__`` folders hold the cache) and how to run more."""

    stderr: str
    copy: Path
    data: Path
    env: dict[str, str]

    def run(self, *args: str) -> subprocess.CompletedProcess[str]:
        done = subprocess.run([BPB, *args], capture_output=True, text=True, env=self.env,
                              timeout=600)  # fmt: skip
        assert done.returncode == 0, done.stderr
        return done


@pytest.fixture(scope="module")
def cold(tmp_path_factory: pytest.TempPathFactory) -> ColdBuild:
    """The one cold build the tests below observe (about 25 s on 2 cores; each test made its
    own): sources numba has never seen (a copy of ``bpb_tasks``), no ``NUMBA_CACHE_DIR``, the
    pool's 2 workers spawned (as on macOS, and Linux's forkserver from Python 3.14: they inherit
    nothing from bpb) and started by ``--stable-only`` before any scene is made."""
    import bpb_tasks

    root = tmp_path_factory.mktemp("cold")
    copy = root / "bpb_tasks"
    shutil.copytree(
        Path(bpb_tasks.__file__).parent, copy, ignore=shutil.ignore_patterns("__pycache__")
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(root), env.get("PYTHONPATH")]))
    args = ["generate", "--out", str(root / "ds"), "--per-horizon", "2", "--horizons", "1",
            "--workers", "2", "--stable-only", "--no-images"]  # fmt: skip
    done = subprocess.run([sys.executable, "-c", SPAWNED_BPB, *args], capture_output=True,
                          text=True, env=env, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return ColdBuild(done.stderr, copy, root / "ds", env)


def _note(where: str) -> str:
    return f"note: {NOTE} (about 20 s); cached in {where} for later commands\n"


def test_workers_that_are_not_forked_load_the_kernel_the_parent_built(cold: ColdBuild) -> None:
    """A first command on a machine compiles for about 20 s: one line on stderr says so, not
    one per worker. Spawned workers inherit nothing from bpb: on a cold cache each built the
    kernel itself (twice the CPU on 2 workers) and gave the note as a raw Python warning, with
    the file and line of bpb's code; and ``--stable-only`` starts its pool before any scene is
    made. The parent makes the first scene, and builds the code, first; the workers load it
    from numba's cache."""
    assert cold.stderr == _note(f"the __pycache__ folders under {cold.copy}")


def test_the_note_names_where_numba_caches_all_of_it_without_numba_cache_dir(
    cold: ColdBuild,
) -> None:
    """Without NUMBA_CACHE_DIR numba caches each compiled module's code in the ``__pycache__``
    beside it: the stability code's and the kernel's in two folders. The note named the first
    one to compile only (``.../billiards/__pycache__``), half of what was built."""
    assert cold.stderr == _note(f"the __pycache__ folders under {cold.copy}")
    for folder in ("billiards", "simulators/analytic"):
        assert list((cold.copy / folder / "__pycache__").glob("*.nbi")), folder


def test_nothing_is_said_once_it_is_cached_and_a_part_built_later_says_so_again(
    cold: ColdBuild,
) -> None:
    """The next command loads the cache silently. ``bpb simulate``'s fast path is code
    generation never ran: built on its first use, said again (the note said "once", then came
    back); then loaded silently."""
    out = str(cold.data.with_name("warm"))
    warm = cold.run("generate", "--out", out, "--per-horizon", "2", "--horizons", "1",
                    "--workers", "2", "--stable-only", "--no-images")  # fmt: skip
    assert warm.stderr == ""
    simulate = ["simulate", str(cold.data), "--engine", "kernel", "--workers", "1"]
    lines = [cold.run(*simulate).stderr for _ in range(2)]
    assert lines == [cold.stderr, ""]


def test_the_note_names_numba_cache_dir_when_it_is_set(tmp_path: Path) -> None:
    """With NUMBA_CACHE_DIR numba caches all compiled code under it (one folder per module
    folder): the note names that folder, the one to keep or clear."""
    (tmp_path / "callee.py").write_text(CALLEE.format(value=1))
    (tmp_path / "caller.py").write_text(CALLER)
    cache = tmp_path / "numba-cache"
    _, stderr = _run_total(tmp_path, {"NUMBA_CACHE_DIR": str(cache)})
    assert f"{NOTE} (about 20 s); cached in {cache} for later commands" in stderr
    assert list(cache.rglob("caller.total-*.nbi"))
