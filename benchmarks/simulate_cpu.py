"""CPU per scene of ``bpb simulate``, start-up excluded: the command runs twice in one process
over the same scene files and only the second run is counted: the first counts the lines
(scenes), the second writes them to ``/dev/null`` through file descriptor 1, as into a file.

Usage: ``python benchmarks/simulate_cpu.py PATH_LIST [ROUNDS]``, where ``PATH_LIST`` names what to
give ``bpb simulate``, one per line: scene files, or a dataset folder. Scenes are counted from
the lines printed. Which code runs is whatever ``bpb_core`` this interpreter imports, so putting
another checkout's ``src`` first on ``PYTHONPATH`` measures that checkout. The first run pays
for the imports, numba's cached kernels and the caches of the code; the counted run is the
steady per-scene cost of reading, validating, simulating and writing.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import time
from pathlib import Path


class _Counting(io.TextIOBase):
    """Standard output thrown away, its lines counted."""

    def __init__(self) -> None:
        self.lines = 0

    def write(self, text: str) -> int:
        self.lines += text.count("\n")
        return len(text)


def run_once(paths: list[str], *, counted: bool = True) -> tuple[float, int]:
    """CPU seconds and scenes of one ``bpb simulate --workers 1 PATHS`` inside this process:
    its lines counted (``counted``), or written to ``/dev/null`` through standard output's file
    descriptor, as into a file a user redirects them to (scenes then 0)."""
    from bpb_core.cli.main import main

    sink = _Counting()
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        with contextlib.ExitStack() as stack:
            if counted:
                stack.enter_context(contextlib.redirect_stdout(sink))
            else:
                os.dup2(null, 1)
            started = time.process_time()
            try:
                main(["simulate", "--workers", "1", *paths])
            except SystemExit as exc:
                if exc.code not in (0, None):
                    raise
            took = time.process_time() - started
            sys.stdout.flush()
    finally:
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)
    return took, sink.lines


def main(listing: str, rounds: int) -> None:
    """Print the warm CPU per scene of each round."""
    paths = Path(listing).read_text().split()
    first, scenes = run_once(paths)
    for r in range(rounds):
        took, _ = run_once(paths, counted=False)
        print(
            f"round {r + 1}: {scenes} scenes, first run {first:.2f} s, counted run "
            f"{took:.2f} s CPU, {took / scenes * 1e6:.1f} us per scene",
            flush=True,
        )


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 1)
