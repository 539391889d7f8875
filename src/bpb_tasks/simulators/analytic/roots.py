"""Root finding of the analytic simulator, one code for the Python engine (float64 or mpmath
numbers) and the compiled event kernel, which compiles these very functions with ``@jit``
(:mod:`~bpb_tasks.simulators.analytic.kernel`), so this module's source keys the kernel's
cache folder as the kernel modules' own do.

Only two moving balls need more than a closed form: their squared centre distance minus
``(2R)^2`` is a quartic ``g(t)`` on the interval where both laws of motion hold. Its first
contact is found without any closed-form quartic formula: the roots of ``g''`` (a quadratic,
closed form) split the interval into pieces where ``g'`` is monotone, a bracketed Newton search
finds the roots of ``g'`` (the critical points of ``g``) on those pieces, and the same search
finds the first root of ``g`` on the first piece where ``g`` falls from positive to non-positive.
Each piece is monotone, so every search has a sign-changing bracket and cannot miss or wander.

Polynomials are 5-tuples (highest degree first, lower degrees padded with leading zeros) and
results fixed-size tuples with a count, so numba compiles them without allocating; the Python
engine runs the same operations in the same order, which gives both the same float64 results.
"""

from __future__ import annotations

import math
from typing import Any

Number = Any  # float, or an mpmath mpf
Poly = tuple[Number, Number, Number, Number, Number]
NO_ROOT = -1.0  # "none": contact times and distances are never negative


def sqrt(x: Number) -> Number:
    """Square root of a float (``math.sqrt``; the kernel compiles it as that) or an mpmath
    number (mpmath computes ``x ** 0.5`` as its square root, at the number's precision)."""
    return math.sqrt(x) if isinstance(x, float | int) else x**0.5


def horner(c: Poly, t: Number) -> Number:
    """Value at ``t`` of the polynomial ``c``."""
    return (((c[0] * t + c[1]) * t + c[2]) * t + c[3]) * t + c[4]


def derivative(c: Poly) -> Poly:
    """Derivative of the quartic (or padded lower-degree polynomial) ``c``."""
    return (0.0, c[0] * 4, c[1] * 3, c[2] * 2, c[3] * 1)


def refine(c: Poly, lo: Number, hi: Number, rising: bool, tol: Number, max_iter: int) -> Number:
    """The root of a polynomial that is monotone on ``[lo, hi]`` with a sign change there.

    Bracketed Newton: a Newton step is taken when it stays inside the bracket, a bisection
    otherwise, so convergence is quadratic near the root and guaranteed in all cases; it stops
    when the bracket is ``tol`` narrow or after ``max_iter`` steps. Returns the bracket end on
    the positive side when ``rising`` is false (the side before a contact).
    """
    slope = derivative(c)
    x = (lo + hi) / 2
    for _ in range(max_iter):
        fx = horner(c, x)
        if fx == 0:
            return x
        if (fx > 0) != rising:
            lo = x
        else:
            hi = x
        if hi - lo <= tol:
            break
        dfx = horner(slope, x)
        step = x - fx / dfx if dfx != 0 else lo
        x = step if lo < step < hi else (lo + hi) / 2
    return lo if not rising else hi


def quadratic_splits(a: Number, b: Number, c: Number, t_max: Number) -> tuple[Number, Number, int]:
    """Real roots of ``a t^2 + b t + c`` (any degenerate case) inside ``(0, t_max)``, sorted,
    and their count.

    Uses the cancellation-free form ``q = -(b + sign(b) sqrt(disc)) / 2``.
    """
    r1 = r2 = 0.0
    count = 0
    if a == 0:
        if b != 0:
            r1, count = -c / b, 1
    else:
        disc = b * b - 4 * a * c
        if disc >= 0:
            root = sqrt(disc)
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


def critical_points(
    c: Poly, t_max: Number, tol: Number, max_iter: int
) -> tuple[Number, Number, Number, int]:
    """Points in ``(0, t_max)`` where the quartic's derivative changes sign, sorted, and their
    count."""
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
            out[n] = refine(slope, lo, hi, f_lo < 0, tol, max_iter)
            n += 1
    return out[0], out[1], out[2], n


def first_contact(c: Poly, t_max: Number, tol: Number, max_iter: int) -> Number:
    """The first ``t`` in ``[0, t_max]`` where the quartic ``g`` reaches zero while falling, or
    :data:`NO_ROOT`.

    ``c`` holds ``g``'s five coefficients; ``g(t) = |d(t)|^2 - (2R)^2``. A pair already
    touching or overlapping (``g(0) <= 0``) collides at 0 only when approaching
    (``g'(0) < 0``); otherwise only a fall from positive to zero counts, and a zero touch with
    ``g' = 0`` (zero normal speed) is not a contact.
    """
    if c[4] <= 0 and c[3] < 0:
        return 0.0
    if t_max <= 0:
        return NO_ROOT
    p1, p2, p3, n = critical_points(c, t_max, tol, max_iter)
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
            root = hi if g_hi == 0 else refine(c, lo, hi, False, tol, max_iter)
            if horner(slope, root) < 0:
                return root
    return NO_ROOT
