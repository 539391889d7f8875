"""``bpb bench generate``: dataset generation time beside PNG encoding alone, and memory.

All timings of one call run on the same machine in one process tree, one after the other, with
the same number of worker processes, so machine noise hits them alike:

* ``generate``: a full dataset of the default scene family (scenes, ground truth and whatever
  the family adds: its images, stats);
* ``generate --no-images``: the same without images (what rendering costs is the difference);
* ``pillow default``: Pillow alone encoding as many images of the same size, RGB with Pillow's
  default PNG settings (what a straightforward renderer pays just to save files);
* ``pillow palette``: the same images encoded by Pillow as 8-bit palette PNGs at zlib level 1.

The images encoded by these baselines are the dataset's own (its family's ``image_names``,
decoded). A family without images gets no encoding rows.
"""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from multiprocessing.pool import Pool
from pathlib import Path
from typing import Literal

from PIL import Image

from bpb_core.bench.children import run_child
from bpb_core.dataset.worker import started_pool, worker_signals

SAMPLE_IMAGES = 24


@dataclass(frozen=True)
class GenerateTiming:
    """Wall seconds of each variant for ``scenes`` scenes (``images`` PNGs)."""

    scenes: int
    images: int
    workers: int
    size: tuple[int, int] | None
    generate_s: float
    no_images_s: float
    pillow_default_s: float | None
    pillow_palette_s: float | None

    @property
    def images_per_scene(self) -> float:
        """Images written per scene."""
        return self.images / self.scenes if self.scenes else 0.0


@dataclass(frozen=True)
class MemoryUse:
    """Peak resident set sizes (MiB) of one ``generate_dataset`` call in a fresh process
    (``worker_mib`` is None with one worker: the scenes are made in the process itself)."""

    scenes: int
    seconds: float
    parent_mib: float
    worker_mib: float | None


Encoder = Literal["pillow default", "pillow palette"]


def _encode_share(args: tuple[list[bytes], int, Encoder]) -> int:
    """Encode ``count`` images cycling through ``sources``; return total bytes written."""
    sources, count, how = args
    images: list[Image.Image] = [Image.open(io.BytesIO(data)) for data in sources]
    if how == "pillow default":
        images = [img.convert("RGB") for img in images]
    else:
        images = [img.convert("P") if img.mode != "P" else img for img in images]
    total = 0
    for i in range(count):
        img = images[i % len(images)]
        out = io.BytesIO()
        if how == "pillow palette":
            img.save(out, format="PNG", compress_level=1)
        else:
            img.save(out, format="PNG")
        total += out.tell()
    return total


def _encode_seconds(sources: list[bytes], count: int, workers: int, how: Encoder) -> float:
    shares = [count // workers + (1 if i < count % workers else 0) for i in range(workers)]
    jobs = [(sources, n, how) for n in shares]
    # Ctrl-C: the parent stops them
    with started_pool(lambda: Pool(workers, initializer=worker_signals)) as pool:
        started = time.perf_counter()
        pool.map(_encode_share, jobs)
        return time.perf_counter() - started


def _images(root: Path) -> list[Path]:
    """The dataset's image files (the names its scene family declares), in scene order."""
    from bpb_core.dataset import load_dataset

    dataset = load_dataset(root)
    found = (dataset.path(key, name) for key in dataset.keys for name in dataset.family.image_names)
    return [path for path in found if path.is_file()]


def _warm(out: Path, horizons: Sequence[float], seed: int) -> None:
    """Generate 1 scene per horizon, unmeasured: on a cold cache this builds the compiled
    physics code (20-60 s of CPU and its memory) and saves it, so a measured generation, in this
    process or a fresh one, loads it instead."""
    from bpb_core.dataset import generate_dataset

    generate_dataset(out, 1, horizons, seed, workers=1)


def measure_generate(
    per_horizon: int = 200,
    horizons: Sequence[float] = (1, 2, 3, 4, 5),
    seed: int = 0,
    workers: int | None = None,
) -> GenerateTiming:
    """Time a dataset generation against encoding as many images alone (see module)."""
    from bpb_core.dataset import generate_dataset

    n_workers = workers or os.cpu_count() or 1
    with tempfile.TemporaryDirectory(prefix="bpb-bench-") as tmp:
        root = Path(tmp)
        _warm(root / "warm", horizons, seed)
        started = time.perf_counter()
        full = generate_dataset(root / "full", per_horizon, horizons, seed, workers=n_workers)
        generate_s = time.perf_counter() - started
        started = time.perf_counter()
        generate_dataset(
            root / "bare", per_horizon, horizons, seed, workers=n_workers, images=False
        )
        no_images_s = time.perf_counter() - started
        images = _images(full)
        sources = [p.read_bytes() for p in images[:SAMPLE_IMAGES]]
    scenes, count = per_horizon * len(horizons), len(images)
    if not sources:
        return GenerateTiming(scenes, 0, n_workers, None, generate_s, no_images_s, None, None)
    with Image.open(io.BytesIO(sources[0])) as first:
        size = first.size
    return GenerateTiming(
        scenes=scenes,
        images=count,
        workers=n_workers,
        size=size,
        generate_s=generate_s,
        no_images_s=no_images_s,
        pillow_default_s=_encode_seconds(sources, count, n_workers, "pillow default"),
        pillow_palette_s=_encode_seconds(sources, count, n_workers, "pillow palette"),
    )


# The process's own peak: its ru_maxrss would start at the bench's (bpb_core.bench.peak). Its
# workers are forked (start methods fork and forkserver), not exec'd, so theirs is their own
# (pages shared with it included); with "spawn" it would start at this process's peak.
_MEMORY_SCRIPT = """
import json, resource, sys, time, warnings
warnings.simplefilter("ignore")
from bpb_core.bench.peak import own_peak_kib
from bpb_core.dataset import generate_dataset
out, per_horizon, workers = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
started = time.perf_counter()
generate_dataset(out, per_horizon, [1, 2, 3, 4, 5], 0, workers=workers)
seconds = time.perf_counter() - started
me = own_peak_kib() or resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
print(json.dumps({"seconds": seconds, "parent_kib": me, "worker_kib": kids}))
"""


def measure_memory(per_horizon: int, workers: int | None = None) -> MemoryUse:
    """Peak RSS of the generating process and of its largest worker, in a fresh interpreter
    (which loads the compiled code this process built first: its build is no part of either)."""
    n_workers = workers or os.cpu_count() or 1
    with tempfile.TemporaryDirectory(prefix="bpb-bench-mem-") as tmp:
        _warm(Path(tmp) / "warm", (1, 2, 3, 4, 5), 0)  # the script's dataset, 1 scene each
        done = run_child(
            [
                sys.executable,
                "-c",
                _MEMORY_SCRIPT,
                str(Path(tmp) / "ds"),
                str(per_horizon),
                str(n_workers),
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
    data = json.loads(done.stdout.strip().splitlines()[-1])
    return MemoryUse(
        scenes=5 * per_horizon,
        seconds=data["seconds"],
        parent_mib=data["parent_kib"] / 1024,
        worker_mib=data["worker_kib"] / 1024 if n_workers > 1 else None,
    )
