"""numba for the compiled event kernel: :func:`jit`, and the plain functions of
:mod:`~bpb_tasks.simulators.analytic.roots` and :mod:`~bpb_tasks.simulators.analytic.motion`
that the Python engine runs too, made callable from compiled code (``register_jitable``, with
``roots.sqrt`` compiled as ``math.sqrt``), so the kernel reproduces the Python engine's float64
results operation for operation.

Without numba the kernel's functions run as plain Python (slowly), which keeps the modules
importable and testable. This is the one module that imports numba; it first points
``NUMBA_CACHE_DIR`` at bpb's cache folder unless the user set it
(:mod:`~bpb_tasks.simulators.analytic.kernel_cache`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from typing import Any, TypeVar

from bpb_tasks.simulators.analytic import motion, roots
from bpb_tasks.simulators.analytic.kernel_cache import cache_folder, note
from bpb_tasks.simulators.analytic.numeric import FLOAT64

F = TypeVar("F", bound=Callable[..., Any])
TIME_TOL = FLOAT64.time_tol
SPEED_TOL = FLOAT64.speed_tol
MAX_ITER = FLOAT64.max_iter

if not os.environ.get("NUMBA_CACHE_DIR"):  # numba reads it as it is imported
    os.environ["NUMBA_CACHE_DIR"] = str(cache_folder())
_numba: Any
try:  # numba is an optional extra (``pip install 'bpb[fast]'``)
    import numba as _numba
except ImportError:
    _numba = None
except Exception as exc:  # an install numba cannot load itself in
    note(f"numba could not be imported ({type(exc).__name__}: {exc}); using the Python engine")
    _numba = None
HAVE_NUMBA = _numba is not None


def _cacheable() -> bool:
    """Whether numba finds a folder it can write its cache in (not on a read-only install
    without a writable home or cache folder: the kernel is then compiled in memory by each
    command that uses it, said once)."""
    try:
        _numba.njit(cache=True)(_cacheable)
    except RuntimeError as exc:  # "cannot cache function ...: no locator available"
        note(f"numba cannot cache the physics kernel ({exc}); each command compiles it anew")
        return False
    return True


CACHE = HAVE_NUMBA and _cacheable()


def jit(func: F) -> F:
    """Compile ``func`` with numba (cached on disk when it can be) when it is installed; else
    return it."""
    if _numba is None:
        return func
    try:
        return _numba.njit(cache=CACHE)(func)  # type: ignore[no-any-return]
    except RuntimeError:  # no cache folder for this module's folder alone: in memory
        return _numba.njit(func)  # type: ignore[no-any-return]


if _numba is not None:  # what jitted code calls of the plain modules, compiled where called
    from numba.extending import overload, register_jitable

    @overload(roots.sqrt)
    def _sqrt(x: float) -> Callable[[float], float]:
        def compiled(x: float) -> float:  # its parameters as ``roots.sqrt``'s, annotations too
            return math.sqrt(x)

        return compiled

    for _plain in (
        roots.horner,
        roots.derivative,
        roots.refine,
        roots.quadratic_splits,
        roots.critical_points,
        roots.first_contact,
        motion.heading,
        motion.time_for,
        motion.line_contact,
        motion.pocket_entry,
        motion.pocket_holding,
        motion.point_segment_gap2,
        motion.moving_contact,
    ):
        register_jitable(_plain)
