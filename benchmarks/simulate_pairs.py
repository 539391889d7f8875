"""``bpb simulate``'s steady CPU per scene, this checkout against another one, side by side.

Usage: ``python benchmarks/simulate_pairs.py PATH_LIST OTHER_SRC [PAIRS]``. ``PATH_LIST`` names what
to give ``bpb simulate`` (see ``simulate_cpu.py``); ``OTHER_SRC`` is the ``src`` folder of the
other checkout (for instance ``git worktree add /tmp/pre 7e5c969`` and ``/tmp/pre/src``), run
with this interpreter and its installed packages. The two alternate, one fresh process each
(``simulate_cpu.py PATH_LIST 1``), ``PAIRS`` times (default 7): a shared machine drifts, so the
ratio is taken pair by pair and the median quoted. Both first print their whole output once and
the script stops unless the bytes are the same.
"""

from __future__ import annotations

import hashlib
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _env(src: str | None) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    if src is not None:
        env["PYTHONPATH"] = src
    return env


def output_digest(paths: list[str], src: str | None) -> str:
    """The md5 of ``bpb simulate --workers 1 PATHS``'s output with ``src`` first on the path."""
    code = "import sys; from bpb_core.cli.main import main; main(sys.argv[1:])"
    done = subprocess.run(
        [sys.executable, "-c", code, "simulate", "--workers", "1", *paths],
        env=_env(src),
        capture_output=True,
        check=True,
    )
    return hashlib.md5(done.stdout).hexdigest()


def per_scene(listing: str, src: str | None) -> float:
    """Microseconds of CPU per scene of one fresh ``simulate_cpu.py`` process."""
    done = subprocess.run(
        [sys.executable, str(HERE / "simulate_cpu.py"), listing, "1"],
        env=_env(src),
        capture_output=True,
        text=True,
        check=True,
    )
    found = re.findall(r"([0-9.]+) us per scene", done.stdout)
    return float(found[-1])


def main(listing: str, other: str, pairs: int) -> None:
    """Print each pair, then medians and ranges."""
    paths = Path(listing).read_text().split()
    if output_digest(paths, None) != output_digest(paths, other):
        sys.exit("the two checkouts print different bytes: nothing to compare")
    rows = []
    for n in range(pairs):
        before, after = per_scene(listing, other), per_scene(listing, None)
        rows.append((before, after))
        print(
            f"pair {n + 1}: other {before:.1f}, this {after:.1f} us per scene, "
            f"{before / after:.2f}x ({time.strftime('%H:%M:%S', time.gmtime())} UTC)",
            flush=True,
        )
    for label, values in (
        ("other", [b for b, _ in rows]),
        ("this", [a for _, a in rows]),
        ("ratio", [b / a for b, a in rows]),
    ):
        middle = statistics.median(values)
        print(f"{label}: median {middle:.2f} ({min(values):.2f}-{max(values):.2f})")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 7)
