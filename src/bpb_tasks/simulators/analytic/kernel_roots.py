"""Root finding of the compiled event kernel: :mod:`bpb_tasks.simulators.analytic.roots` for
float64 only, with polynomials as 5-tuples (highest degree first, lower degrees padded with
leading zeros) so numba compiles them without allocating.

Every expression keeps the operand order of the reference code, so the kernel reproduces the
Python engine's float64 results operation for operation. Without numba the functions run as plain
Python (slowly), which keeps the module importable and testable.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib
import inspect
import math
import os
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from bpb_core.errors import Notice

F = TypeVar("F", bound=Callable[..., Any])
TIME_TOL = 1e-15  # FLOAT64.time_tol
SPEED_TOL = 1e-15  # FLOAT64.speed_tol
MAX_ITER = 200  # FLOAT64.max_iter
NO_ROOT = -1.0  # contact times are never negative

_numba: Any
try:  # numba is an optional extra (``pip install 'bpb[fast]'``)
    _numba = importlib.import_module("numba")
except ImportError:  # pragma: no cover - exercised where numba is absent
    _numba = None
HAVE_NUMBA = _numba is not None


def jit(func: F) -> F:
    """Compile ``func`` with numba (cached on disk) when it is installed; else return it.

    numba checks a cached function against its own file only, yet the cached machine code
    holds every compiled function it calls, from other files too: after an edit or upgrade of
    a callee's file alone (``git pull`` on an editable install), the caller would go on running
    the old callee. The cache of a function made here is therefore also stamped with
    :func:`kernel_sources_stamp`, so a change to any compiled module it may call recompiles it.
    """
    if _numba is None:
        return func
    cache_class = _stamped_cache_class()
    compiled: Any = _numba.njit(cache=cache_class is None)(func)  # not numba's cache, then ours
    if cache_class is not None:
        compiled._cache = cache_class(func)  # what Dispatcher.enable_caching sets, stamped
    return compiled  # type: ignore[no-any-return]


JIT_MARK = "@jit"
"""How a module's compiled functions are marked; the modules holding it are stamped."""


@functools.cache
def _folder_stamp(folder: Path) -> bytes:
    """SHA-256 over the names and contents of ``folder``'s Python files with compiled
    functions (those holding :data:`JIT_MARK`), in name order."""
    digest = hashlib.sha256()
    for path in sorted(folder.glob("*.py")):
        data = path.read_bytes()
        if JIT_MARK.encode() in data:
            digest.update(path.name.encode() + b"\0" + hashlib.sha256(data).digest())
    return digest.digest()


def kernel_sources_stamp(func: Callable[..., Any]) -> tuple[bytes, bytes]:
    """What the cache of compiled ``func`` is also stamped with: the compiled modules of this
    folder (the kernel every compiled function builds on) and of ``func``'s own folder."""
    return _folder_stamp(Path(__file__).parent), _folder_stamp(Path(inspect.getfile(func)).parent)


@functools.cache
def _stamped_cache_class() -> type | None:
    """numba's per-function cache with :func:`kernel_sources_stamp` added to the source stamp
    it checks (``None`` where this numba's caching internals differ: plain caching then)."""
    try:
        from numba.core.caching import CompileResultCacheImpl, FunctionCache
        from numba.core.runtime.nrt import rtsys
    except ImportError:  # pragma: no cover - other numba versions
        return None

    class Stamped:
        """A cache locator giving its source stamp with the kernel sources' stamp."""

        def __init__(self, inner: Any, extra: tuple[bytes, bytes]) -> None:
            self._inner, self._extra = inner, extra

        def get_source_stamp(self) -> Any:
            return (self._inner.get_source_stamp(), self._extra)

        def __getattr__(self, name: str) -> Any:
            return getattr(self._inner, name)

    class StampedImpl(CompileResultCacheImpl):
        def __init__(self, py_func: Callable[..., Any]) -> None:
            super().__init__(py_func)  # type: ignore[no-untyped-call]
            self._locator = Stamped(self._locator, kernel_sources_stamp(py_func))

    class StampedCache(FunctionCache):
        _impl_class = StampedImpl

        def load_overload(self, sig: Any, target_context: Any) -> Any:
            """numba's lookup, which the dispatcher makes before it compiles: nothing loaded
            means it compiles now (see :func:`note_compiling`).

            numba refreshes the target context first, importing and installing all its
            lowering code (about 0.25 s of CPU, once per process: a fifth of a small ``bpb
            generate``). Cached machine code needs none of it, only the symbols it links to:
            numba's C helpers and the C maths, there since the context was made, and those
            of the runtime (NRT) and of the hash secret, added here. Compiling refreshes the
            context itself (numba's ``CompilerBase``). Should the code need more (another
            numba), that load fails and numba's own, with the refresh, is made instead."""
            try:
                rtsys.initialize(target_context)
                importlib.import_module("numba.cpython.hashing")  # the hash secret's symbols
                with self._guard_against_spurious_io_errors():
                    loaded = self._load_overload(sig, target_context)  # type: ignore[no-untyped-call]
            except Exception:  # whatever it was, numba's own load decides
                loaded = super().load_overload(sig, target_context)  # type: ignore[no-untyped-call]
            if loaded is None and self._enabled:
                note_compiling(cache_root(self._cache_path, Path(inspect.getfile(self._py_func))))
            return loaded

    if not hasattr(CompileResultCacheImpl, "locator") or not hasattr(
        FunctionCache, "_load_overload"
    ):  # pragma: no cover
        return None
    return StampedCache


class CompileNotice(Notice):
    """The compiled kernel is about to be built: numba's cache holds no code for this machine
    and these sources (a first use, or after an upgrade or edit)."""


COMPILE_NOTE = (
    "compiling the physics kernel for this machine (about 20 s); cached in {} for later commands"
)
"""Each part is built on its first use: a command that runs code no earlier one did (``bpb
simulate``'s fast path after ``bpb generate``, say) builds that part then, and says so again."""
_noted = False  # one note per process; workers forked after it inherit it


def cache_root(cache_path: str, source: Path) -> str:
    """Where numba caches the code of every compiled module, from ``cache_path``, where it caches
    ``source``'s: beside each module (its ``__pycache__``; the compiled modules are in this
    package, ``bpb_tasks``, and ``source``'s folder: the note comes with the first function
    built, which may be the kernel's or the stability code's), or in one folder per module
    folder under a cache folder (``NUMBA_CACHE_DIR``, else a user-wide one where the package's
    is not writable)."""
    path = Path(cache_path)
    if path.name != "__pycache__":
        return str(path.parent)
    common = os.path.commonpath([source.parent, Path(__file__).parents[2]])
    return f"the __pycache__ folders under {common}"


def note_compiling(cache_path: str) -> None:
    """Warn once per process (:class:`CompileNotice`) that compiled code is being built, naming
    where numba caches it (``NUMBA_CACHE_DIR`` when set, else ``cache_path``: see
    :func:`cache_root`): the first build of the kernel and the stability code costs about 20 s
    of CPU, silent otherwise."""
    global _noted
    if _noted:
        return
    _noted = True
    where = getattr(getattr(_numba, "config", None), "CACHE_DIR", "") or cache_path
    with contextlib.suppress(CompileNotice):  # warnings made errors: a note must not stop it
        warnings.warn(COMPILE_NOTE.format(where), CompileNotice, stacklevel=2)


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
