"""Paths of the repository the tests read (docs, fixtures)."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs"
FIXTURES = REPO / "tests" / "fixtures"
