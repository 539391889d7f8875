"""Paths of the repository the tests read (docs, fixtures)."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs"
FIXTURES = REPO / "tests" / "fixtures"


def tree(root: Path) -> dict[str, bytes]:
    """Every file under ``root`` by its ``/``-separated relative path, with its bytes: a folder
    compared byte for byte before and after a command."""
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*") if p.is_file()}
