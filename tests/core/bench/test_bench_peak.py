"""Peak memory figures of ``bpb bench run`` and ``bench generate`` are the measured process's own.

On Linux a child's ``ru_maxrss`` starts at the high-water mark of the process that started it:
a bench holding hundreds of MB used to report that much for every client it measured.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from support.processes import HAS_PROC

HOG_MIB = 800
"""What the measuring process holds: far above what any measured process here needs."""

pytestmark = pytest.mark.skipif(not HAS_PROC, reason="own peak RSS is read from /proc (Linux)")


@pytest.fixture
def hog() -> Iterator[None]:
    """This process holds HOG_MIB of resident memory (every page written) for the test."""
    held = b"\x01" * (HOG_MIB << 20)
    yield
    del held


@pytest.mark.usefixtures("hog")
def test_bench_run_reports_each_client_s_own_peak_not_the_bench_s(tmp_path: Path) -> None:
    from bpb_core.bench.run import bench_dataset, bench_throughput

    data = bench_dataset(tmp_path, 1)
    bare, ours = bench_throughput(data, concurrency=4, latency=0.01, scenes_per_horizon=1, rounds=1)
    for phase in (bare, ours):
        assert phase.exit_code == 0, phase.error
        assert 10 < phase.peak_rss_mb < HOG_MIB / 2, phase  # own use: about 215 and 305 MB


@pytest.mark.usefixtures("hog")
def test_bench_generate_reports_the_generating_process_s_own_peak() -> None:
    from bpb_core.bench.generate import measure_memory

    used = measure_memory(1, workers=1)
    assert 10 < used.parent_mib < HOG_MIB / 2, used
