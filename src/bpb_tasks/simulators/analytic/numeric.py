"""Numeric backends: the same simulator code runs on float64 or on mpmath numbers.

The analytic simulator only uses ``+ - * /``, comparisons, ``roots.sqrt`` and
:attr:`Numeric.num` (to lift an input float). Python floats and ``mpmath`` numbers both support
the operators, so choosing a backend at construction is all it takes to run the identical
algorithm in 50-digit arithmetic, which is the reference in tests and in ``bpb bench sim``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

Number = Any  # float, or an mpmath mpf of the backend's context


@dataclass(frozen=True)
class Numeric:
    """A number system for the simulator.

    Attributes:
        name: ``float64`` or ``mpmath<digits>``.
        num: Lifts a Python float (exactly) into the backend.
        time_tol: Root refinement stops when the bracket is this narrow (seconds).
        max_iter: Upper bound on refinement iterations per root.
        speed_tol: Two touching balls whose approach speed is at most this fraction of the sum
            of their speeds do not collide: the exchange would be lost in the rounding of the
            speeds (the backend's relative precision, with a margin).
    """

    name: str
    num: Callable[[float], Number]
    time_tol: Number
    max_iter: int
    speed_tol: Number


FLOAT64 = Numeric("float64", float, 1e-15, 200, 1e-15)


def backend(precision: str | int | None) -> Numeric:
    """The backend named by ``precision``: ``None``/``"float64"``, or a digit count for mpmath
    (that many significant decimal digits, on a private mpmath context: the global
    ``mpmath.mp`` precision is left untouched)."""
    if precision is None or precision == "float64":
        return FLOAT64
    try:
        digits = int(precision)
    except ValueError:
        digits = 0
    if digits < 20:
        from bpb_core.errors import BadInput

        raise BadInput(f"--precision: expected 'float64' or a digit count >= 20, got {precision!r}")
    import mpmath

    ctx = mpmath.MPContext()
    ctx.dps = digits
    tol = ctx.mpf(10) ** (-(digits - 8))
    return Numeric(f"mpmath{digits}", ctx.mpf, tol, 400, tol)
