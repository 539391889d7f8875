"""Root finding of the compiled event kernel: :mod:`bpb_tasks.simulators.analytic.roots` for
float64 only, with polynomials as 5-tuples (highest degree first, lower degrees padded with
leading zeros) so numba compiles them without allocating.

Every expression keeps the operand order of the reference code, so the kernel reproduces the
Python engine's float64 results operation for operation. Without numba the functions run as plain
Python (slowly), which keeps the module importable and testable. This is the one module that
imports numba; it first points ``NUMBA_CACHE_DIR`` at bpb's cache folder unless the user set it
(:mod:`~bpb_tasks.simulators.analytic.kernel_cache`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from typing import Any, TypeVar

from bpb_tasks.simulators.analytic.kernel_cache import cache_folder, note

F = TypeVar("F", bound=Callable[..., Any])
TIME_TOL = 1e-15  # FLOAT64.time_tol
SPEED_TOL = 1e-15  # FLOAT64.speed_tol
MAX_ITER = 200  # FLOAT64.max_iter
NO_ROOT = -1.0  # contact times are never negative

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


Poly = tuple[float, float, float, float, float]


@jit
def horner(c: Poly, t: float) -> float:
    """Value at ``t`` of the polynomial ``c`` (see the module docstring for the layout)."""
    return (((c[0] * t + c[1]) * t + c[2]) * t + c[3]) * t + c[4]


@jit
def derivative(c: Poly) -> Poly:
    """Derivative of the quartic (or padded lower-degree polynomial) ``c``."""
    return (0.0, c[0] * 4, c[1] * 3, c[2] * 2, c[3] * 1)


@jit
def refine(c: Poly, lo: float, hi: float, rising: bool) -> float:
    """Bracketed Newton on a monotone piece (reference: ``roots.refine``)."""
    slope = derivative(c)
    x = (lo + hi) / 2
    for _ in range(MAX_ITER):
        fx = horner(c, x)
        if fx == 0:
            return x
        if (fx > 0) != rising:
            lo = x
        else:
            hi = x
        if hi - lo <= TIME_TOL:
            break
        dfx = horner(slope, x)
        step = x - fx / dfx if dfx != 0 else lo
        x = step if lo < step < hi else (lo + hi) / 2
    return lo if not rising else hi


@jit
def quadratic_splits(a: float, b: float, c: float, t_max: float) -> tuple[float, float, int]:
    """Real roots of ``a t^2 + b t + c`` inside ``(0, t_max)``, sorted, and their count."""
    r1 = r2 = 0.0
    count = 0
    if a == 0:
        if b != 0:
            r1, count = -c / b, 1
    else:
        disc = b * b - 4 * a * c
        if disc >= 0:
            root = math.sqrt(disc)
            q = -(b + root) / 2 if b >= 0 else -(b - root) / 2
            if q == 0:
                r1, count = q / a, 1
            else:
                r1, r2, count = q / a, c / q, 2
    k1 = count >= 1 and 0 < r1 < t_max
    k2 = count >= 2 and 0 < r2 < t_max
    if k1 and k2:
        return (r1, r2, 2) if r1 <= r2 else (r2, r1, 2)
    if k1:
        return r1, 0.0, 1
    if k2:
        return r2, 0.0, 1
    return 0.0, 0.0, 0


@jit
def critical_points(c: Poly, t_max: float) -> tuple[float, float, float, int]:
    """Sign changes of the quartic's derivative in ``(0, t_max)``, sorted, and their count."""
    slope = derivative(c)
    curve = derivative(slope)
    s1, s2, ns = quadratic_splits(curve[2], curve[3], curve[4], t_max)
    edges = (0.0, s1, s2, t_max)
    if ns == 0:
        edges = (0.0, t_max, t_max, t_max)
    elif ns == 1:
        edges = (0.0, s1, t_max, t_max)
    out = [0.0, 0.0, 0.0]
    n = 0
    for j in range(ns + 1):
        lo, hi = edges[j], edges[j + 1]
        f_lo, f_hi = horner(slope, lo), horner(slope, hi)
        if (f_lo < 0 < f_hi) or (f_lo > 0 > f_hi):
            out[n] = refine(slope, lo, hi, f_lo < 0)
            n += 1
    return out[0], out[1], out[2], n


@jit
def first_contact(c: Poly, t_max: float) -> float:
    """First falling zero of the quartic in ``[0, t_max]`` or :data:`NO_ROOT`
    (reference: ``roots.first_contact``)."""
    if c[4] <= 0 and c[3] < 0:
        return 0.0
    if t_max <= 0:
        return NO_ROOT
    p1, p2, p3, n = critical_points(c, t_max)
    edges = (0.0, p1, p2, p3, t_max)
    if n == 0:
        edges = (0.0, t_max, t_max, t_max, t_max)
    elif n == 1:
        edges = (0.0, p1, t_max, t_max, t_max)
    elif n == 2:
        edges = (0.0, p1, p2, t_max, t_max)
    slope = derivative(c)
    for j in range(n + 1):
        lo, hi = edges[j], edges[j + 1]
        g_lo, g_hi = horner(c, lo), horner(c, hi)
        if g_lo > 0 >= g_hi:
            root = hi if g_hi == 0 else refine(c, lo, hi, False)
            if horner(slope, root) < 0:
                return root
    return NO_ROOT
