"""Fill numba's cache of every compiled function bpb runs (``python -m support.compiled_code``).

A ``bpb`` command that has to build them (a fresh clone, an edit of a compiled module) says so
in one ``note:`` line on stderr; the suite builds them first, once, so that tests reading a
command's stderr whole see only what the command itself says. With a warm cache this only
loads them (about a second).
"""

from __future__ import annotations

import importlib.util
import warnings


def fill() -> None:
    """Make and simulate in a batch one scene: the code of ``bpb generate`` (scene,
    stability), of calibration and of ``bpb simulate``'s batches."""
    if importlib.util.find_spec("numba") is None:
        return
    from bpb_tasks.billiards.family import BilliardsFamily
    from bpb_tasks.simulators.analytic.engine import AnalyticSimulator

    warnings.simplefilter("ignore")  # the note, when it builds
    family, simulator = BilliardsFamily(), AnalyticSimulator(engine="kernel")
    made = family.make_scene(family.load_config(None), simulator, 0, 1.0, 0)
    assert len(family.ground_truths([made.scene], simulator)) == 1


if __name__ == "__main__":
    fill()
