"""Where the compiled kernel is cached, when a command uses it, and that whatever happens to
numba or its cache ``bpb generate`` writes the same bytes and exits 0.

The commands run in subprocesses (what numba imports, and what it finds on disk, is per
process); they load the session's warm cache (``tests/conftest.py``) or use none: no test
here compiles the kernel.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from bpb_tasks.simulators.analytic import engine
from bpb_tasks.simulators.analytic.engine import (
    COMPILE_SECONDS,
    cache_folder,
    is_cached,
    python_seconds,
    sources_hash,
    use_kernel,
)

GENERATE = ["generate", "--per-horizon", "3", "--horizons", "1,3", "--workers", "1"]
RUN_BPB = "import sys\n{}\nfrom bpb_core.cli.main import main\nmain(sys.argv[1:])"


def test_the_cache_folder_follows_every_compiled_module_and_bpb_s_version(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """numba checks a cached function against its own file only, yet its code holds every
    compiled function it calls: the folder is keyed by all compiled modules' sources."""
    (tmp_path / "a.py").write_text("@jit\ndef f():\n    return 1\n")
    (tmp_path / "b.py").write_text("def g():\n    return 2\n")
    monkeypatch.setattr(engine, "__file__", str(tmp_path / "x" / "y" / "engine.py"))
    before = sources_hash()
    (tmp_path / "b.py").write_text("def g():\n    return 3\n")  # not compiled: same folder
    assert sources_hash() == before
    (tmp_path / "a.py").write_text("@jit\ndef f():\n    return 2\n")
    assert sources_hash() != before
    monkeypatch.setattr(engine, "__version__", "9.9.9")
    assert cache_folder().name == f"9.9.9-{sources_hash()[:16]}"


def test_the_engine_is_chosen_by_the_work() -> None:
    copies = python_seconds(64, 5)  # a generated scene's perturbed copies
    assert copies < COMPILE_SECONDS < python_seconds(64, 100_000)  # a long scene's are not
    assert not use_kernel("auto", True, False, 0.0, copies)  # a small command does not compile
    assert use_kernel("auto", True, False, 0.0, COMPILE_SECONDS)
    assert use_kernel("auto", True, False, COMPILE_SECONDS - copies, copies)  # so far counts
    assert use_kernel("auto", True, True, 0.0, copies)  # cached: loaded, not built
    assert use_kernel("kernel", True, False, 0.0, 0.0)
    assert not use_kernel("python", True, True, 0.0, COMPILE_SECONDS)
    assert not use_kernel("auto", False, True, 0.0, COMPILE_SECONDS)  # no numba, or mpmath


def test_the_session_cache_holds_the_kernel() -> None:
    pytest.importorskip("numba")
    assert is_cached(Path(os.environ["NUMBA_CACHE_DIR"]))


def _generate(out: Path, env: dict[str, str], setup: str = "") -> subprocess.CompletedProcess[str]:
    done = subprocess.run(
        [sys.executable, "-c", RUN_BPB.format(setup), *GENERATE, "--out", str(out)],
        capture_output=True,
        text=True,
        env={**os.environ, **env},
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    return done


def _files(root: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()
    }


@pytest.fixture(scope="module")
def kernel_made(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """A small dataset made with the compiled kernel (the session cache is warm)."""
    pytest.importorskip("numba")
    out = tmp_path_factory.mktemp("kernel") / "ds"
    assert _generate(out, {}).stderr == ""  # loaded, not built: nothing said
    return _files(out)


def test_without_numba_generate_writes_the_same_bytes(
    kernel_made: dict[str, bytes], tmp_path: Path
) -> None:
    done = _generate(tmp_path / "ds", {}, "sys.modules['numba'] = None  # import numba fails")
    assert done.stderr == "" and _files(tmp_path / "ds") == kernel_made


def test_without_a_writable_cache_folder_or_home_generate_writes_the_same_bytes(
    kernel_made: dict[str, bytes], tmp_path: Path
) -> None:
    """A read-only install: no cache folder numba can write (under a regular file, which no
    user can create a folder in, root included), no home, and the package's ``__pycache__``
    folders regular files too. The kernel, asked for, is compiled in memory; the command's
    own small work takes the Python engine."""
    blocked = tmp_path / "file.txt"
    blocked.write_text("")
    copy = tmp_path / "site" / "bpb_tasks"
    shutil.copytree(Path(engine.__file__).parents[2], copy,
                    ignore=shutil.ignore_patterns("__pycache__"))  # fmt: skip
    for folder in [copy, *(p for p in copy.rglob("*") if p.is_dir())]:
        (folder / "__pycache__").write_text("")
    path = os.pathsep.join(filter(None, [str(copy.parent), os.environ.get("PYTHONPATH")]))
    env = {"NUMBA_CACHE_DIR": str(blocked / "sub"), "HOME": str(blocked),
           "XDG_CACHE_HOME": str(blocked / "cache"), "PYTHONPATH": path}  # fmt: skip
    done = _generate(tmp_path / "ds", env)
    assert done.stderr == "" and _files(tmp_path / "ds") == kernel_made
    probe = subprocess.run(
        [sys.executable, "-c", "from bpb_tasks.simulators.analytic import kernel as k\n"
         "print(k.CACHE, k.__file__)"],
        capture_output=True, text=True, env={**os.environ, **env}, timeout=600,
    )  # fmt: skip
    assert probe.returncode == 0, probe.stderr
    assert probe.stdout.split() == ["False", str(copy / "simulators/analytic/kernel.py")]
    assert probe.stderr.count("KernelNotice: numba cannot cache the physics kernel") == 1


def test_with_a_truncated_cache_generate_writes_the_same_bytes(
    kernel_made: dict[str, bytes], tmp_path: Path
) -> None:
    """Every ``.nbi``/``.nbc`` file of a warm cache cut in half: numba's load raises
    (UnpicklingError); the command says so in one note and runs the Python engine."""
    cache = tmp_path / "cache"
    shutil.copytree(os.environ["NUMBA_CACHE_DIR"], cache)
    cut = [p for p in cache.rglob("*") if p.suffix in (".nbi", ".nbc")]
    assert cut
    for p in cut:
        p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    done = _generate(tmp_path / "ds", {"NUMBA_CACHE_DIR": str(cache)})
    assert _files(tmp_path / "ds") == kernel_made
    (line,) = done.stderr.splitlines()
    assert line.startswith("note: the compiled physics kernel cannot be used (")
    assert line.endswith("); using the Python engine")
