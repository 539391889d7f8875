"""``bpb generate`` of the paper-size dataset as users run it, this checkout against another one,
each beside the CPU of encoding its own PNGs alone.

Usage: ``python benchmarks/generate_pairs.py OTHER_SRC [PAIRS] [FOLDER]``. ``OTHER_SRC`` is the
``src`` folder of the other checkout (``git worktree add /tmp/pre c8c8f10``, then ``/tmp/pre/src``),
run with this interpreter and its installed packages. Each pair runs ``bpb generate --out
FOLDER/x --per-horizon 200 --overwrite`` (default workers) once with the other checkout and once
with this one, in turn, the order swapped every pair (``FOLDER`` defaults to ``/dev/shm``, where
creating files costs no disk time). A run's CPU is the operating system's count for the command
and the workers it reaped (user + system). Right after each run, a fresh process decodes that
dataset's 3,000 scene PNGs (not counted) and encodes them alone, counting only that: with
Pillow at zlib level 1 (how bpb stored them until stop 31, issue 12's yardstick) and with bpb's
own writer (``bpb_tasks.billiards.render.png``, zlib-ng at its default level: how bpb stores them
now). Every run of one checkout must write the same ``checksums.sha256``; the script stops
otherwise.
"""

from __future__ import annotations

import json
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

from simulate_pairs import _env  # benchmarks/ is first on the path of a script

HERE = Path(__file__).resolve().parent
ENCODE = """
import json, sys
from pathlib import Path
sys.path.insert(0, sys.argv[2])
from generate_cpu import encode_cpu
paths = sorted(Path(sys.argv[1]).glob("h*/scene_*/*.png"))
print(json.dumps([len(paths), *encode_cpu(paths)]))
"""


def generate(out: Path, src: str | None) -> tuple[float, float, str]:
    """CPU and wall seconds of one ``bpb generate`` (paper size) and its checksums."""
    code = "import sys; from bpb_core.cli.main import main; main(sys.argv[1:])"
    args = ["generate", "--out", str(out), "--per-horizon", "200", "--overwrite"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run(
        [sys.executable, "-c", code, *args], env=_env(src), check=True, capture_output=True
    )
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall, (out / "checksums.sha256").read_text()


def encode_alone(out: Path) -> tuple[int, float, float]:
    """Images, then CPU seconds of encoding them alone with Pillow and with bpb's writer."""
    done = subprocess.run(
        [sys.executable, "-c", ENCODE, str(out), str(HERE)],
        env=_env(None),
        check=True,
        capture_output=True,
        text=True,
    )
    count, pillow, own = json.loads(done.stdout)
    return int(count), float(pillow), float(own)


def main(other: str, pairs: int, folder: Path) -> None:
    """Print every run, then medians and ranges per checkout."""
    seen: dict[str, str] = {}
    rows: dict[str, list[tuple[float, float, float, float]]] = {"other": [], "this": []}
    for n in range(pairs):
        order = [("other", other), ("this", None)]
        for label, src in order if n % 2 == 0 else order[::-1]:
            out = folder / f"bpb-pairs-{label}"
            cpu, wall, checksums = generate(out, src)
            if seen.setdefault(label, checksums) != checksums:
                sys.exit(f"{label}: a run wrote other files than the first: nothing to compare")
            count, pillow, own = encode_alone(out)
            rows[label].append((cpu, wall, pillow, own))
            print(
                f"pair {n + 1} {label}: generate {cpu:.2f} s CPU ({wall:.2f} s wall); its "
                f"{count} PNGs alone: Pillow {pillow:.2f} s ({cpu / pillow:.3f}x), bpb's "
                f"writer {own:.2f} s ({cpu / own:.3f}x) "
                f"({time.strftime('%H:%M:%S', time.gmtime())} UTC)",
                flush=True,
            )
    for label, runs in rows.items():
        for name, values in (
            ("generate CPU s", [r[0] for r in runs]),
            ("wall s", [r[1] for r in runs]),
            ("Pillow alone s", [r[2] for r in runs]),
            ("bpb's writer alone s", [r[3] for r in runs]),
            ("ratio to Pillow", [r[0] / r[2] for r in runs]),
            ("ratio to bpb's writer", [r[0] / r[3] for r in runs]),
        ):
            middle = statistics.median(values)
            print(f"{label} {name}: median {middle:.3f} ({min(values):.3f}-{max(values):.3f})")
    ratio = [a[0] / b[0] for a, b in zip(rows["this"], rows["other"], strict=True)]
    print(f"this/other CPU per pair: median {statistics.median(ratio):.3f} "
          f"({min(ratio):.3f}-{max(ratio):.3f})")  # fmt: skip


if __name__ == "__main__":
    main(
        sys.argv[1],
        int(sys.argv[2]) if len(sys.argv) > 2 else 5,
        Path(sys.argv[3]) if len(sys.argv) > 3 else Path("/dev/shm"),
    )
