"""Inspect AI's entry point (group ``inspect_ai``, name ``bpb``): importing it registers
``bpb/q1``, ``bpb/q2``, ``bpb/q3`` and ``bpb/total`` with Inspect."""

from __future__ import annotations

from bpb.inspect_tasks import q1, q2, q3, total

__all__ = ["q1", "q2", "q3", "total"]
