"""CPU per scene of ``bpb simulate``, start-up excluded: the command runs twice in one process
over the same scene files (output to ``/dev/null``) and only the second run is counted.

Usage: ``python scripts/simulate_cpu.py FILE_LIST [ROUNDS]``, where ``FILE_LIST`` names one scene
file per line. Which code runs is whatever ``bpb_core`` this interpreter imports, so putting
another checkout's ``src`` first on ``PYTHONPATH`` measures that checkout. The first run pays
for the imports, numba's cached kernels and the caches of the code; the counted run is the
steady per-scene cost of reading, validating, simulating and writing.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from pathlib import Path


def run_once(files: list[str]) -> float:
    """CPU seconds of one ``bpb simulate --workers 1 FILES`` inside this process."""
    from bpb_core.cli.main import main

    started = time.process_time()
    with open(os.devnull, "w") as sink, contextlib.redirect_stdout(sink):
        try:
            main(["simulate", "--workers", "1", *files])
        except SystemExit as exc:
            if exc.code not in (0, None):
                raise
    return time.process_time() - started


def main(listing: str, rounds: int) -> None:
    """Print the warm CPU per scene of each round."""
    files = Path(listing).read_text().split()
    first = run_once(files)
    for r in range(rounds):
        took = run_once(files)
        print(
            f"round {r + 1}: {len(files)} scenes, first run {first:.2f} s, counted run "
            f"{took:.2f} s CPU, {took / len(files) * 1e6:.1f} us per scene",
            flush=True,
        )


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 1)
