"""A scene family whose hooks of ``bpb bench sim`` (bench_scenes, compare, events,
scaled_scene, the bench_* attributes) raise or give the wrong type is one line naming its plugin
and the hook, exit 3.

Before, a compare() that raised, and bench_scenes() of dicts, were counted as failed scenes of
every simulator (exit 1, figures written, the simulators blamed); a compare() without
"error" was "error: scene family: compare() returned no 'error'" (exit 2, naming no plugin); an
events() of floats went into the µs/event figure (exit 0); a bench_contestants string was read
letter by letter ("unknown simulator 'f'", exit 2); the others were internal errors (an
AttributeError, a TypeError) naming no plugin. A bench_reference property that raised escaped
isinstance(family, Comparing) itself on Python 3.11 ("internal error: RuntimeError: ...").
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

import support.flawed_family

ORIGIN = "plugin 'flawed' (flawed_family) from bpb-flawed 1.2"
FAMILY = "scene family 'flawed'"
SCALING = ["--scaling", "flawed-analytic", "--scaling-scenes", "1"]
FLAWS = [
    ("bench_reference_type", [], "bench_reference is NoneType; expected a str"),
    ("bench_reference_raise", [], "reading bench_reference raised RuntimeError: "
     "bench_reference exploded"),
    ("bench_contestants_type", [], "bench_contestants is str; expected a tuple of simulator "
     "specs (str)"),
    ("bench_scenes_raise", [], "bench_scenes(2, 0) raised RuntimeError: bench_scenes exploded"),
    ("bench_scenes_type", [], "bench_scenes(2, 0) returned a scene of type dict; expected Scene "
     "(the family's scene_model)"),
    ("compare_raise", [], "compare() raised RuntimeError: compare exploded"),
    ("compare_no_error", [], "compare() returned no 'error'; expected a dict of named numbers "
     "holding 'error'"),
    ("compare_type", [], "compare() returned {'error': str, ...}; expected a dict of named "
     "numbers holding 'error'"),
    ("events_type", [], "events() returned float; expected a count (an int at least 0)"),
    ("scaled_scene_raise", SCALING, "scaled_scene() raised RuntimeError: scaled_scene exploded"),
    ("scaled_scene_type", SCALING, "scaled_scene() returned dict; expected a scene like the one "
     "it was given (Scene)"),
]  # fmt: skip


@pytest.fixture
def bench_sim(install: Any, site: Path, bench: Any, monkeypatch: pytest.MonkeyPatch) -> Any:
    source = Path(support.flawed_family.__file__).read_text()
    install("bpb-flawed", "1.2", {"flawed_family": source}, {"flawed": "flawed_family"})
    monkeypatch.syspath_prepend(str(site))  # installed: its entry point is found
    return lambda *extra: bench("sim", "--family", "flawed", "--scenes", "2",
                                "--simulate-scenes", "0", *extra)  # fmt: skip


def test_the_flawed_family_benches_without_a_flaw(bench_sim: Any) -> None:
    done = bench_sim(*SCALING)
    assert done.returncode == 0, done.stderr
    assert "flawed-analytic:precision=50 (reference)" in done.stdout


@pytest.mark.parametrize(("flaw", "extra", "said"), FLAWS)
def test_bpb_bench_sim_is_one_line_naming_the_family_plugin_and_exit_3(
    bench_sim: Any, monkeypatch: pytest.MonkeyPatch, flaw: str, extra: list[str], said: str
) -> None:
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    done = bench_sim(*extra)
    assert done.returncode == 3, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"error: {ORIGIN}: {FAMILY}: {said} (set BPB_DEBUG=1 for a traceback)"
    ]
