"""The ``analytic`` simulator: exact event-driven billiards.

``engine`` runs the event loop and finds each pair's next event on the float64 or mpmath number
backends, ``motion`` holds the closed forms of one ball's motion and ``roots`` the polynomial
root finding, both compiled into the numba ``kernel`` too.
"""

from bpb_tasks.simulators.analytic.engine import AnalyticSimulator, SimulationError

__all__ = ["AnalyticSimulator", "SimulationError"]
