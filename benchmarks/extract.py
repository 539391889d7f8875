"""Answer extraction (``bpb_core.extract``) on adversarial and chain-of-thought replies.

Usage: ``python benchmarks/extract.py [--repeats N]``. Each reply is built at 250 kB, 500 kB
and 1 MB; one pass over the text should make the time grow at most linearly with the size.
Two tables: adversarial replies with the last-valid rule (any JSON value validates), plus the
first rule at 1 MB; and Q1 replies through the q1 task's own parser with chain of thought, whose
reasoning is LaTeX (``\\frac{a}{b}``: thousands of brace groups). The target is under 50 ms for
any 1 MB reply that holds its answer; a reply where nothing validates has every brace group
tried, and its time is printed beside them. Prints the best of ``--repeats`` per size and
exits 1 when a 1 MB reply holding its answer is slower than the target.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import random
import sys
import time
from collections.abc import Callable

from bpb_core import ParseFailure, PromptOptions, extract, make_registry
from bpb_tasks.billiards.scene.model import Ball, Scene

TARGET_MS = 50.0
SIZES = (250_000, 500_000, 1_000_000)
Q1_ANSWER = json.dumps({"answers": [{"id": i, "answer": "F"} for i in range(1, 7)]}, indent=2)


def _mixed(size: int) -> str:
    rng = random.Random(0)
    return "".join(rng.choice('{}"\\a :,[]') for _ in range(size))


def _latex(size: int) -> str:
    """Reasoning as a model writes it, cut to ``size`` characters: an unclosed ``\\left\\{``, a
    quote, then steps of four brace groups each."""
    parts = ['$d = \\left\\{ 2R$ so ball 3 is "T".\n']
    length = len(parts[0])
    while length < size:
        k = len(parts)
        parts.append(f"Step {k}: $s_{{{k}}} = \\frac{{v_0^2 - v_{{{k}}}^2}}{{2 \\mu g}}$.\n")
        length += len(parts[-1])
    return "".join(parts)[:size]


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
# Q1 replies: name -> (builder, holds its answer)
Q1_REPLIES: dict[str, tuple[Callable[[int], str], bool]] = {
    "LaTeX reasoning, answer last": (lambda n: _latex(n - len(Q1_ANSWER)) + Q1_ANSWER, True),
    "LaTeX reasoning, no answer": (_latex, False),
    "{} pairs, no answer": (lambda n: "{}" * (n // 2), False),
}


def best_ms(run: Callable[[str], object], text: str, repeats: int) -> float:
    """The quickest of ``repeats`` calls of ``run`` on ``text``, in milliseconds (parse failures
    count)."""
    best = float("inf")
    for _ in range(repeats):
        started = time.perf_counter()
        with contextlib.suppress(ParseFailure):
            run(text)
        best = min(best, time.perf_counter() - started)
    return best * 1000


def _last_valid(text: str) -> object:
    return extract(text, lambda value: value, cot=True)


def _first(text: str) -> object:
    return extract(text, lambda value: value, cot=False)


def _q1_parser() -> Callable[[str], object]:
    task = make_registry().task("q1")
    balls = [Ball(id=i, pos=(0.2 + 0.2 * i, 0.5), vel=(0.0, 0.0)) for i in range(7)]
    scene = Scene(scene_id="h1/scene_0000", horizon=1.0, balls=balls)
    options = PromptOptions(cot=True)
    return lambda text: task.parse(text, scene, options)


def _row(name: str, times: list[float], extra: str = "") -> str:
    ratio = times[-1] / times[0] if times[0] > 0.05 else float("nan")
    return f"{name:30}" + "".join(f"{ms:12.2f}" for ms in times) + f"{ratio:16.1f}{extra}"


def _header(first: str) -> str:
    sizes = "".join(f"{s // 1000:>9,} kB" for s in SIZES)
    return f"{first:30}{sizes}  1 MB / 250 kB"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed repeats (best kept)")
    repeats = max(1, parser.parse_args().repeats)
    slow = False
    print(_header("reply (last-valid)") + "   first, 1 MB")
    for family, build in FAMILIES.items():
        texts = [build(size) for size in SIZES]
        row = [best_ms(_last_valid, text, repeats) for text in texts]
        first = best_ms(_first, texts[-1], repeats)
        slow = slow or row[-1] > TARGET_MS
        print(_row(family, row, f"{first:14.2f}"))
    parse = _q1_parser()
    print("\n" + _header("Q1 reply (q1 parser, CoT)") + "   groups, 1 MB")
    for name, (build, answered) in Q1_REPLIES.items():
        texts = [build(size) for size in SIZES]
        row = [best_ms(parse, text, repeats) for text in texts]
        slow = slow or (answered and row[-1] > TARGET_MS)
        print(_row(name, row, f"{texts[-1].count('}'):14,}"))
    print(f"target: under {TARGET_MS:g} ms on any 1 MB reply holding its answer: ", end="")
    print("missed" if slow else "met")
    sys.exit(1 if slow else 0)


if __name__ == "__main__":
    main()
