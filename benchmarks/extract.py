"""Answer extraction (``bpb_core.extract``) on adversarial replies of growing size.

Usage: ``python benchmarks/extract.py [--repeats N]``. Each family of reply is built at 250 kB,
500 kB and 1 MB; one pass over the text should make the time grow linearly with the size, and
the target is under 50 ms for any 1 MB reply. Prints the best of ``--repeats`` per size and
exits 1 when a 1 MB reply is slower than the target.
"""

from __future__ import annotations

import argparse
import contextlib
import random
import sys
import time
from collections.abc import Callable

from bpb_core import ParseFailure, extract

TARGET_MS = 50.0
SIZES = (250_000, 500_000, 1_000_000)


def _mixed(size: int) -> str:
    rng = random.Random(0)
    return "".join(rng.choice('{}"\\a :,[]') for _ in range(size))


FAMILIES: dict[str, Callable[[int], str]] = {
    "unclosed {": lambda n: "{" * n,
    'nested {"a":': lambda n: '{"a":' * (n // 5),
    "{ then {} pairs": lambda n: "{" + "{}" * (n // 2),
    "deep {{..}}": lambda n: "{" * (n // 2) + "}" * (n // 2),
    "unclosed string": lambda n: '{"' + "x" * n,
    "escaped quotes": lambda n: '{"' + '\\"' * (n // 2),
    'empty strings ""': lambda n: "{" + '"",' * (n // 3),
    "random braces/quotes": _mixed,
    "prose, answer last": lambda n: "The body moves. " * (n // 16) + '{"answer": 1}',
}


def best_ms(text: str, repeats: int) -> float:
    """The quickest of ``repeats`` extractions of ``text``, in milliseconds."""
    best = float("inf")
    for _ in range(repeats):
        started = time.perf_counter()
        with contextlib.suppress(ParseFailure):
            extract(text, lambda value: value, cot=True)
        best = min(best, time.perf_counter() - started)
    return best * 1000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed repeats (best kept)")
    repeats = max(1, parser.parse_args().repeats)
    print(f"{'reply':24}" + "".join(f"{s // 1000:>9,} kB" for s in SIZES) + "  1 MB / 250 kB")
    slow = False
    for family, build in FAMILIES.items():
        row = [best_ms(build(size), repeats) for size in SIZES]
        slow = slow or row[-1] > TARGET_MS
        ratio = row[-1] / row[0] if row[0] > 0.05 else float("nan")
        print(f"{family:24}" + "".join(f"{ms:12.2f}" for ms in row) + f"{ratio:16.1f}")
    print(f"target: under {TARGET_MS:g} ms on any 1 MB reply: {'missed' if slow else 'met'}")
    sys.exit(1 if slow else 0)


if __name__ == "__main__":
    main()
