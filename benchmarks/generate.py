"""Dataset generation time beside PNG encoding alone, and optionally peak memory.

Usage: ``python benchmarks/generate.py [--per-horizon N] [--workers N] [--memory N,N,...]``.
All timings run one after the other with the same number of worker processes, so machine noise
hits them alike (wall seconds):

* ``generate``: a dataset of the default scene family (scenes, ground truth, images, stats);
* ``generate, no images``: the same without images (rendering costs the difference);
* Pillow alone encoding as many images of the same size, as RGB with Pillow's default PNG
  settings (what a straightforward renderer pays to save files), and as 8-bit palette PNGs at
  zlib level 1.

The images encoded are the dataset's own (its family's ``image_names``, decoded). One scene per
horizon is generated first, unmeasured, so a cold compiled-code cache is built before timing.
``--memory`` runs ``generate_dataset`` at each size in a fresh interpreter and prints its own
peak resident set (``VmHWM``, not the one ``exec`` inherits) and its largest worker's.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import subprocess
import sys
import tempfile
import time
from multiprocessing import Pool
from pathlib import Path

from PIL import Image

from bpb_core import generate_dataset, load_dataset

HORIZONS = (1, 2, 3, 4, 5)
SAMPLE_IMAGES = 24


def encode_share(args: tuple[list[bytes], int, str]) -> int:
    """Encode ``count`` images cycling through ``sources`` (``rgb`` or ``palette``)."""
    sources, count, how = args
    images = [Image.open(io.BytesIO(data)) for data in sources]
    images = [img.convert("RGB" if how == "rgb" else "P") for img in images]
    total = 0
    for i in range(count):
        out = io.BytesIO()
        if how == "rgb":
            images[i % len(images)].save(out, format="PNG")
        else:
            images[i % len(images)].save(out, format="PNG", compress_level=1)
        total += out.tell()
    return total


def encode_seconds(sources: list[bytes], count: int, workers: int, how: str) -> float:
    """Wall seconds of ``workers`` processes encoding ``count`` images between them."""
    shares = [count // workers + (1 if i < count % workers else 0) for i in range(workers)]
    with Pool(workers) as pool:
        started = time.perf_counter()
        pool.map(encode_share, [(sources, n, how) for n in shares])
        return time.perf_counter() - started


def timed_generate(out: Path, per_horizon: int, workers: int, images: bool = True) -> float:
    started = time.perf_counter()
    generate_dataset(out, per_horizon, HORIZONS, 0, workers=workers, images=images)
    return time.perf_counter() - started


def measure(per_horizon: int, workers: int) -> None:
    """Print the generation and encoding rows."""
    with tempfile.TemporaryDirectory(prefix="bpb-bench-") as tmp:
        root = Path(tmp)
        generate_dataset(root / "warm", 1, HORIZONS, 0, workers=1)
        full = timed_generate(root / "full", per_horizon, workers)
        bare = timed_generate(root / "bare", per_horizon, workers, images=False)
        dataset = load_dataset(root / "full")
        names = dataset.family.image_names
        paths = [dataset.path(key, name) for key in dataset.keys for name in names]
        paths = [path for path in paths if path.is_file()]
        sources = [p.read_bytes() for p in paths[:SAMPLE_IMAGES]]
    scenes, count = per_horizon * len(HORIZONS), len(paths)
    rows = [("bpb generate", full), ("bpb generate, no images", bare)]
    if sources:
        for how, label in (("rgb", "RGB PNGs, default"), ("palette", "palette PNGs, level 1")):
            seconds = encode_seconds(sources, count, workers, how)
            rows.append((f"Pillow alone: {count} {label}", seconds))
    print(f"{scenes} scenes, {count} images, {workers} worker(s)")
    print(f"{'variant':48}{'seconds':>10}{'ms/scene':>10}")
    for name, seconds in rows:
        print(f"{name:48}{seconds:10.2f}{1000 * seconds / scenes:10.2f}")


MEMORY_SCRIPT = """
import json, resource, sys, time
from pathlib import Path
from bpb_core import generate_dataset
out, per_horizon, workers = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
started = time.perf_counter()
generate_dataset(out, per_horizon, [1, 2, 3, 4, 5], 0, workers=workers)
seconds = time.perf_counter() - started
status = Path("/proc/self/status")
own = [int(l.split()[1]) for l in status.read_text().splitlines() if l.startswith("VmHWM:")]
kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
print(json.dumps({"seconds": seconds, "parent_kib": own[0], "worker_kib": kids}))
"""


def memory(per_horizon: int, workers: int) -> None:
    """Print the peak resident sets of one generation in a fresh interpreter."""
    with tempfile.TemporaryDirectory(prefix="bpb-bench-mem-") as tmp:
        argv = [sys.executable, "-c", MEMORY_SCRIPT, str(Path(tmp) / "d"), str(per_horizon)]
        done = subprocess.run([*argv, str(workers)], capture_output=True, text=True, check=True)
    data = json.loads(done.stdout.strip().splitlines()[-1])
    worker = f"{data['worker_kib'] / 1024:.1f}" if workers > 1 else "-"  # none with 1 worker
    print(
        f"memory, {5 * per_horizon} scenes: {data['seconds']:.1f} s, parent peak "
        f"{data['parent_kib'] / 1024:.1f} MiB, largest worker {worker} MiB"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-horizon", type=int, default=200, help="scenes per horizon (x5)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--memory", default="", help="also peak RSS at these sizes: 200,2000")
    args = parser.parse_args()
    measure(args.per_horizon, args.workers)
    for size in (int(x) for x in args.memory.split(",") if x.strip()):
        memory(size, args.workers)


if __name__ == "__main__":
    main()
