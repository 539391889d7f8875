"""CPU of ``bpb generate`` (paper size, images, 64-perturbation stability) beside the CPU of
encoding its PNGs alone, measured in one process, rounds interleaved.

Usage: ``python scripts/generate_cpu.py [ROUNDS]``. Generation runs in this process
(``workers=1``), so ``time.process_time`` holds all of its CPU. The encoding baseline decodes the
dataset's own PNGs first (not counted), then encodes every one of them as bpb stores them
(8-bit palette, zlib level 1) and counts only that.
"""

from __future__ import annotations

import io
import sys
import tempfile
import time
from pathlib import Path

from PIL import Image

from bpb_core.dataset import generate_dataset


def encode_cpu(paths: list[Path]) -> float:
    """CPU seconds to encode the images at ``paths`` (decoded beforehand, not counted)."""
    images = []
    for path in paths:
        with Image.open(path) as img:
            img.load()
            images.append(img.copy())
    started = time.process_time()
    for img in images:
        img.save(io.BytesIO(), format="PNG", compress_level=1)
    return time.process_time() - started


def main(rounds: int) -> None:
    """Print generate CPU, encode CPU and their ratio per round."""
    for r in range(rounds):
        with tempfile.TemporaryDirectory() as tmp:
            started = time.process_time()
            root = generate_dataset(Path(tmp) / "d", 200, [1, 2, 3, 4, 5], 0, workers=1)
            generate = time.process_time() - started
            paths = sorted(Path(root).rglob("*.png"))
            paths = [p for p in paths if p.parent.name.startswith("scene_")]
            encode = encode_cpu(paths)
        print(
            f"round {r + 1}: generate {generate:.1f} s CPU, encoding its {len(paths)} PNGs alone "
            f"{encode:.1f} s CPU, ratio {generate / encode:.2f}",
            flush=True,
        )


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 2)
