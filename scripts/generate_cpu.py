"""CPU of ``bpb generate`` (paper size, images, 64-perturbation stability) beside the CPU of
encoding its PNGs alone, measured in one process, rounds interleaved.

Usage: ``python scripts/generate_cpu.py [ROUNDS]``. Generation runs in this process
(``workers=1``), so ``time.process_time`` holds all of its CPU. The encoding baseline decodes the
dataset's own PNGs first (not counted), then encodes every one of them as bpb stores them
(8-bit palette, zlib level 1) and counts only that.

Generation's CPU is also split into user and system time: creating files costs system time,
and on some file systems far more than on others (on the benchmark machine creating a file in
``/tmp`` cost about 0.7 ms of kernel CPU, in ``/var/tmp`` about 0.03 ms). The dataset goes to a
temporary folder under ``$TMPDIR`` (default ``/tmp``), so set ``TMPDIR`` to compare.
"""

from __future__ import annotations

import io
import resource
import sys
import tempfile
import time
from pathlib import Path

from PIL import Image

from bpb_core.dataset import generate_dataset


def encode_cpu(paths: list[Path]) -> float:
    """CPU seconds to encode the images at ``paths`` (decoded beforehand, not counted)."""
    images: list[Image.Image] = []
    for path in paths:
        with Image.open(path) as opened:
            opened.load()
            images.append(opened.copy())
    started = time.process_time()
    for img in images:
        img.save(io.BytesIO(), format="PNG", compress_level=1)
    return time.process_time() - started


def main(rounds: int) -> None:
    """Print generate CPU, encode CPU and their ratio per round."""
    for r in range(rounds):
        with tempfile.TemporaryDirectory() as tmp:
            before = resource.getrusage(resource.RUSAGE_SELF)
            started = time.process_time()
            root = generate_dataset(Path(tmp) / "d", 200, [1, 2, 3, 4, 5], 0, workers=1)
            generate = time.process_time() - started
            after = resource.getrusage(resource.RUSAGE_SELF)
            system = after.ru_stime - before.ru_stime
            paths = sorted(Path(root).rglob("*.png"))
            paths = [p for p in paths if p.parent.name.startswith("scene_")]
            encode = encode_cpu(paths)
        print(
            f"round {r + 1}: generate {generate:.1f} s CPU ({generate - system:.1f} user, "
            f"{system:.1f} system), encoding its {len(paths)} PNGs alone {encode:.1f} s CPU, "
            f"ratio {generate / encode:.2f} (user time only {(generate - system) / encode:.2f})",
            flush=True,
        )


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 2)
