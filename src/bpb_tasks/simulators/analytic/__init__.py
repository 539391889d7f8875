"""The ``analytic`` simulator: exact event-driven billiards.

``engine`` runs the event loop, ``prediction`` finds each pair's next event, ``motion`` holds the
closed forms of one ball's motion, ``roots`` the polynomial root finding and ``numeric`` the
float64 and mpmath number backends.
"""

from bpb_tasks.simulators.analytic.engine import AnalyticSimulator, SimulationError

__all__ = ["AnalyticSimulator", "SimulationError"]
