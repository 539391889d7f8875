"""CPU of ``bpb generate`` (paper size, images, 64-perturbation stability) beside the CPU of
encoding its PNGs alone, measured in one process, rounds interleaved.

Usage: ``python benchmarks/generate_cpu.py [ROUNDS]``. Generation runs in this process
(``workers=1``), so ``time.process_time`` holds all of its CPU. The encoding baselines decode the
dataset's own PNGs first (not counted), then encode every one of them and count only that: once
with Pillow (8-bit palette, zlib level 1: how bpb stored them until stop 31, the yardstick of
issue 12), once with bpb's own writer (zlib-ng, its default level: how bpb stores them now).

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
from bpb_tasks.billiards.render.png import encode_palette_png
from bpb_tasks.billiards.scene.config import ImageConfig


def encode_cpu(paths: list[Path]) -> tuple[float, float]:
    """CPU seconds to encode the images at ``paths`` (decoded beforehand, not counted) with
    Pillow at zlib level 1 and with bpb's writer."""
    images: list[Image.Image] = []
    for path in paths:
        with Image.open(path) as opened:
            opened.load()
            images.append(opened.copy())
    started = time.process_time()
    for img in images:
        img.save(io.BytesIO(), format="PNG", compress_level=1)
    pillow = time.process_time() - started
    started = time.process_time()
    for img in images:
        encode_palette_png(img, ImageConfig().compress_level)
    return pillow, time.process_time() - started


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
            pillow, own = encode_cpu(paths)
        print(
            f"round {r + 1}: generate {generate:.2f} s CPU ({generate - system:.2f} user, "
            f"{system:.2f} system); encoding its {len(paths)} PNGs alone: Pillow {pillow:.2f} s "
            f"CPU, ratio {generate / pillow:.3f}; bpb's writer {own:.2f} s, ratio "
            f"{generate / own:.3f}; beside bpb's encoding {generate - own:.2f} s",
            flush=True,
        )


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 2)
