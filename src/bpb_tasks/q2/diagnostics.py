"""Diagnostics of Q2: the confusion of the cue ball's wall contacts, pooled and per wall."""

from __future__ import annotations

from bpb_tasks.questions.label_diagnostics import ConfusionDiagnostic


class Q2Confusion(ConfusionDiagnostic):
    """Q2 confusion pooled over the walls (``all``) and per wall, per run."""

    name = "q2_confusion"
    title = "Q2 confusion (all walls and per wall; answered units)"
    task = "q2"
    per_unit = True
