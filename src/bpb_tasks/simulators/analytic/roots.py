"""Root finding for the analytic simulator, written once for every numeric backend.

Only two moving balls need more than a closed form: their squared centre distance minus
``(2R)^2`` is a quartic ``g(t)`` on the interval where both laws of motion hold. Its first
contact is found without any closed-form quartic formula: the roots of ``g''`` (a quadratic,
closed form) split the interval into pieces where ``g'`` is monotone, a bracketed Newton search
finds the roots of ``g'`` (the critical points of ``g``) on those pieces, and the same search
finds the first root of ``g`` on the first piece where ``g`` falls from positive to non-positive.
Each piece is monotone, so every search has a sign-changing bracket and cannot miss or wander.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence

from bpb_tasks.simulators.analytic.numeric import Number, Numeric


def quadratic_roots(
    a: Number, b: Number, c: Number, sqrt: Callable[[Number], Number]
) -> list[Number]:
    """Real roots of ``a t^2 + b t + c`` (any degenerate case), in no particular order.

    Uses the cancellation-free form ``q = -(b + sign(b) sqrt(disc)) / 2``.
    """
    if a == 0:
        return [] if b == 0 else [-c / b]
    disc = b * b - 4 * a * c
    if disc < 0:
        return []
    root = sqrt(disc)
    q = -(b + root) / 2 if b >= 0 else -(b - root) / 2
    if q == 0:
        return [q / a]
    return [q / a, c / q]


def horner(coeffs: Sequence[Number], t: Number) -> Number:
    """Evaluate a polynomial whose coefficients are given highest degree first."""
    value = coeffs[0]
    for c in coeffs[1:]:
        value = value * t + c
    return value


def derivative(coeffs: Sequence[Number]) -> list[Number]:
    """Coefficients (highest first) of the derivative."""
    n = len(coeffs) - 1
    return [c * (n - k) for k, c in enumerate(coeffs[:-1])]


def refine(
    coeffs: Sequence[Number], lo: Number, hi: Number, rising: bool, numeric: Numeric
) -> Number:
    """The root of a polynomial that is monotone on ``[lo, hi]`` with a sign change there.

    Bracketed Newton: a Newton step is taken when it stays inside the bracket, a bisection
    otherwise, so convergence is quadratic near the root and guaranteed in all cases. Returns the
    bracket end on the positive side when ``rising`` is false (the side before a contact).
    """
    slope = derivative(coeffs)
    x = (lo + hi) / 2
    for _ in range(numeric.max_iter):
        fx = horner(coeffs, x)
        if fx == 0:
            return x
        if (fx > 0) != rising:
            lo = x
        else:
            hi = x
        if hi - lo <= numeric.time_tol:
            break
        dfx = horner(slope, x)
        step = x - fx / dfx if dfx != 0 else lo
        x = step if lo < step < hi else (lo + hi) / 2
    return lo if not rising else hi


def critical_points(coeffs: Sequence[Number], t_max: Number, numeric: Numeric) -> list[Number]:
    """Points in ``(0, t_max)`` where the quartic's derivative changes sign, sorted."""
    slope = derivative(coeffs)
    curve = derivative(slope)
    splits = sorted(
        r for r in quadratic_roots(curve[0], curve[1], curve[2], numeric.sqrt) if 0 < r < t_max
    )
    edges = [numeric.num(0.0), *splits, t_max]
    points: list[Number] = []
    for lo, hi in itertools.pairwise(edges):
        f_lo, f_hi = horner(slope, lo), horner(slope, hi)
        if (f_lo < 0 < f_hi) or (f_lo > 0 > f_hi):
            points.append(refine(slope, lo, hi, f_lo < 0, numeric))
    return points


def first_contact(coeffs: Sequence[Number], t_max: Number, numeric: Numeric) -> Number | None:
    """The first ``t`` in ``[0, t_max]`` where the quartic ``g`` reaches zero while falling.

    ``coeffs`` are ``g``'s five coefficients, highest first; ``g(t) = |d(t)|^2 - (2R)^2``. A
    pair already touching or overlapping (``g(0) <= 0``) collides at 0 only when approaching
    (``g'(0) < 0``); otherwise only a fall from positive to zero counts, and a zero touch with
    ``g' = 0`` (zero normal speed) is not a contact.
    """
    g0, g1 = coeffs[4], coeffs[3]
    if g0 <= 0 and g1 < 0:
        return numeric.num(0.0)
    if t_max <= 0:
        return None
    edges = [numeric.num(0.0), *critical_points(coeffs, t_max, numeric), t_max]
    slope = derivative(coeffs)
    for lo, hi in itertools.pairwise(edges):
        g_lo, g_hi = horner(coeffs, lo), horner(coeffs, hi)
        if g_lo > 0 >= g_hi:
            root = hi if g_hi == 0 else refine(coeffs, lo, hi, False, numeric)
            if horner(slope, root) < 0:
                return root
    return None
