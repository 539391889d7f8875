"""``bpb bench generate``'s timed and memory figures leave out the compiled code's one-off
build."""

from __future__ import annotations

from pathlib import Path

import pytest

from support.compiled_code import on_a_cold_cache

SCRIPT = """
import json
import bpb_core.dataset
from bpb_core.bench.generate import measure_generate
from bpb_tasks.simulators.analytic import kernel_roots

calls, builds = [], []  # each generation in turn; the generation each build happened in
generate, note = bpb_core.dataset.generate_dataset, kernel_roots.note_compiling

def counted_generate(*args, **kwargs):
    calls.append(args[0])
    return generate(*args, **kwargs)

def counted_note(*args, **kwargs):
    builds.append(len(calls) - 1)
    return note(*args, **kwargs)

bpb_core.dataset.generate_dataset, kernel_roots.note_compiling = counted_generate, counted_note
measure_generate(1, (1, 2), workers=1)
print(json.dumps({"generations": len(calls), "builds_in": sorted(set(builds))}))
"""


@pytest.mark.slow
def test_a_cold_compile_cache_is_not_counted_in_the_generation_time(tmp_path: Path) -> None:
    """On a cold cache the first generation built the physics kernel (20-60 s) inside the timed
    figure; the build now happens in an untimed generation before the timed ones."""
    seen = on_a_cold_cache(SCRIPT, tmp_path)
    assert seen["generations"] == 3  # the untimed one, then the timed with and without images
    assert seen["builds_in"] == [0]  # every build in the untimed first one


MEMORY_SCRIPT = """
import json, os, pathlib
import bpb_core.bench.generate as bench
from bpb_tasks.simulators.analytic import kernel_roots

cache = pathlib.Path(os.environ["NUMBA_CACHE_DIR"])
events = []  # builds in this process, then what the measured fresh interpreter did
note, run_child = kernel_roots.note_compiling, bench.run_child

def counted_note(*args, **kwargs):
    events.append("build")
    return note(*args, **kwargs)

def files():
    return sorted((str(p), p.stat().st_mtime_ns) for p in cache.rglob("*") if p.is_file())

def counted_child(*args, **kwargs):
    before = files()
    done = run_child(*args, **kwargs)
    events.append("child built" if files() != before else "child loaded")
    return done

kernel_roots.note_compiling, bench.run_child = counted_note, counted_child
bench.measure_memory(1, workers=1)
print(json.dumps(sorted(set(events), key=events.index)))
"""


@pytest.mark.slow
def test_a_cold_compile_cache_is_not_counted_in_the_memory_figures(tmp_path: Path) -> None:
    """The memory figure's fresh interpreter built the physics kernel (20-60 s, and the
    compiler's memory in its peak) on a cold cache; it now loads what the bench built first.
    numba writes the cache files of what it builds, so an unchanged cache means no build."""
    assert on_a_cold_cache(MEMORY_SCRIPT, tmp_path) == ["build", "child loaded"]
