"""Where numba caches the compiled kernel, and when a command uses it.

The cache folder is keyed by bpb's version and a hash of every compiled module's source
(:func:`cache_folder`), so an edit or upgrade of any of them, callee or caller, starts a new
folder: numba itself checks a cached function against its own file only. Unless the user set
``NUMBA_CACHE_DIR``, :mod:`~bpb_tasks.simulators.analytic.kernel` sets it to that folder
before it imports numba. Nothing here imports numba.

:func:`use_kernel` is the engine choice: the compiled kernel when it is cached, or when the
work of a command is worth building it; the Python engine otherwise.
"""

from __future__ import annotations

import contextlib
import hashlib
import warnings
from collections.abc import Mapping
from pathlib import Path

import platformdirs

from bpb_core.errors import Notice
from bpb_core.version import __version__

JIT_MARK = b"@jit"
"""How a module's compiled functions are marked; the modules holding it are hashed."""
ENTRY_POINTS = ("run_arrays", "run_many_arrays", "copy_masks")
"""The compiled functions Python calls; the kernel is cached when numba holds all three."""
PYTHON_SECONDS_PER_RUN = 2e-4
"""The Python engine's CPU time per simulated scene or perturbed copy, besides its events."""
PYTHON_SECONDS_PER_EVENT = 1e-4
"""The Python engine's CPU time per event."""
COMPILE_SECONDS = 20.0
"""The CPU time numba takes to build the kernel's entry points."""


class KernelNotice(Notice):
    """Something about the compiled kernel the user should know: it is being built, or it
    cannot be cached or loaded and bpb goes on without (the Python engine, or uncached code)."""


def sources_hash() -> str:
    """SHA-256 over the paths and contents of bpb_tasks' compiled modules, in path order."""
    root = Path(__file__).parents[2]
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        data = path.read_bytes()
        if JIT_MARK in data:
            digest.update(path.relative_to(root).as_posix().encode() + b"\0")
            digest.update(hashlib.sha256(data).digest())
    return digest.hexdigest()


def cache_folder() -> Path:
    """bpb's own numba cache folder: ``<user cache>/numba/<version>-<sources hash>``."""
    base = Path(platformdirs.user_cache_dir("bpb"))
    return base / "numba" / f"{__version__}-{sources_hash()[:16]}"


def numba_cache_dir(environ: Mapping[str, str]) -> Path:
    """The folder numba caches in given ``environ``: ``NUMBA_CACHE_DIR``, else bpb's own."""
    given = environ.get("NUMBA_CACHE_DIR")
    return Path(given) if given else cache_folder()


def is_cached(folder: Path) -> bool:
    """Whether ``folder`` holds an index of each of the kernel's :data:`ENTRY_POINTS`."""
    try:
        return all(any(folder.rglob(f"*.{name}-*.nbi")) for name in ENTRY_POINTS)
    except OSError:
        return False


def python_seconds(runs: int, events: float) -> float:
    """The Python engine's estimated CPU time for ``runs`` simulations of ``events`` each."""
    return runs * (PYTHON_SECONDS_PER_RUN + events * PYTHON_SECONDS_PER_EVENT)


def use_kernel(engine: str, available: bool, cached: bool, spent: float, seconds: float) -> bool:
    """Whether a batch the Python engine would take ``seconds`` for (:func:`python_seconds`)
    takes the compiled kernel.

    ``engine`` is ``"kernel"``, ``"python"`` or ``"auto"``; ``available``: numba is installed
    and the numbers are float64; ``cached``: the kernel is cached or already loaded;
    ``spent``: the Python engine's estimated CPU seconds so far in this simulator. ``auto``
    builds the kernel only once the Python engine's estimated time, with this batch, would
    reach the build's, so a command smaller than that never builds it."""
    if engine == "python" or not available:
        return False
    if engine == "kernel" or cached:
        return True
    return spent + seconds >= COMPILE_SECONDS


def note(text: str) -> None:
    """Say ``text`` as a :class:`KernelNotice` (a ``note:`` line from the CLI)."""
    with contextlib.suppress(KernelNotice):  # warnings made errors: a note must not stop it
        warnings.warn(text, KernelNotice, stacklevel=3)
