"""A report built from Python leaves the calling program's matplotlib as it found it: a
notebook's inline backend (here: svg) still draws after ``build_report``."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bpb_core.report.build import build_report
from support.reports_fixture import write_runs


@pytest.fixture
def host_backend() -> Iterator[str]:
    import matplotlib

    before = matplotlib.get_backend()
    matplotlib.use("svg")
    try:
        yield matplotlib.get_backend()
    finally:
        matplotlib.use(before)


def test_build_report_keeps_the_callers_matplotlib_backend(
    host_backend: str, tmp_path: Path
) -> None:
    import matplotlib

    report = build_report(write_runs(tmp_path), tmp_path / "out", n_boot=20, gallery_size=0)
    assert list((tmp_path / "out" / "charts").glob("*.png"))
    assert report.tables["leaderboard"] is not None
    assert matplotlib.get_backend() == host_backend
    assert matplotlib.rcParams["backend"] == host_backend
