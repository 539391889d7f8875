"""Diagnostics of Q1: the confusion of the cue ball's contacts, pooled over the object balls."""

from __future__ import annotations

from bpb_tasks.questions.label_diagnostics import ConfusionDiagnostic


class Q1Confusion(ConfusionDiagnostic):
    """Q1 confusion over all object balls: tp, fp, fn, tn, precision, recall, F1 per run."""

    name = "q1_confusion"
    title = "Q1 confusion (all object balls; answered units)"
    task = "q1"
