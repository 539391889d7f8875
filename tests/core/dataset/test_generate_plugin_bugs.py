"""A scene family's load_config(), make_scene() (run in the pool's workers) or write_stats()
that raises or returns the wrong type is one line naming the family's plugin and the hook, exit
3, from ``bpb generate``; the dataset it was to overwrite is left as it was. So are its
check_config(), simulator_name(), physics(), new_tally() and the add() and summary() of the
tally it returns, calibrate_horizon() and apply_calibration(), and its constructor in the pool's
workers.

Before, each came out as "internal error: RuntimeError: ..." naming no plugin, or as an
AttributeError or TypeError from the code that took the value next ("'FinalState' object has no
attribute 'truth'", "'list' object has no attribute 'items'"); write_stats() returning a single
path was read letter by letter (a FileNotFoundError for ``.data.partial/s``), and a path it
never wrote was a FileNotFoundError too. A tally's summary() holding a NaN was written into
dataset.json as is (exit 0, a file JSON parsers refuse).
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pytest

import support.flawed_family
from bpb_core.dataset import generate_dataset
from bpb_core.registry import PluginSource, make_registry
from support.paths import tree

ORIGIN = "plugin 'flawed' (flawed_family) from bpb-flawed 1.2"
FAMILY = "scene family 'flawed'"
MAKE = "make_scene('h1_0001')"
FLAWS = [
    ("load_config_raise", "load_config() raised ValueError: load_config exploded"),
    ("load_config_type", "load_config() returned dict; expected DatasetConfig (the family's "
     "config_model)"),
    ("make_scene_raise", f"{MAKE} raised RuntimeError: make_scene exploded"),
    ("make_scene_type", f"{MAKE} returned FinalState; expected a bpb_core.GeneratedScene (truth "
     "with scene_id and stable, row, files())"),
    ("files_type", "make_scene('h1_0000')'s files() returned list; expected a dict of file names "
     "(str) and their contents (bytes)"),
    ("write_stats_raise", "write_stats() raised RuntimeError: write_stats exploded"),
    ("write_stats_type", "write_stats() returned str; expected a list of the paths it wrote "
     "(str, relative to the dataset folder)"),
    ("write_stats_missing", "write_stats() returned 'stats/never.png', which is no file it wrote "
     "in the dataset folder"),
    ("check_config_raise", "check_config() raised RuntimeError: check_config exploded"),
    ("simulator_name_type", "simulator_name() returned None; expected a simulator's name (str)"),
    ("physics_raise", "physics() raised RuntimeError: physics exploded"),
    ("physics_type", "physics() returned what dataset.json cannot hold (a NaN or "
     "infinity); expected a dict of JSON values"),
    ("new_tally_raise", "new_tally(1) raised RuntimeError: new_tally exploded"),
    ("new_tally_type", "new_tally(1) returned dict; expected a tally with add(row) and summary()"),
    ("tally_add_raise", "new_tally(1)'s add() raised RuntimeError: add exploded"),
    ("tally_summary_raise", "new_tally(1)'s summary() raised RuntimeError: summary exploded"),
    ("tally_summary_type", "new_tally(1)'s summary() returned what dataset.json cannot hold (a "
     "list, not a dict); expected a dict of JSON values"),
    ("tally_summary_nan", "new_tally(1)'s summary() returned what dataset.json cannot hold (a "
     "NaN or infinity); expected a dict of JSON values"),
    ("tally_summary_scenes", "new_tally(1)'s summary() returned 'scenes', which bpb counts "
     "itself; expected the family's own fields"),
]  # fmt: skip
CALIBRATE_FLAWS = [
    ("calibrate_horizon_raise", "calibrate_horizon(1) raised RuntimeError: calibrate_horizon "
     "exploded"),
    ("apply_calibration_raise", "apply_calibration() raised RuntimeError: apply_calibration "
     "exploded"),
    ("apply_calibration_type", "apply_calibration() returned (dict, DatasetConfig); expected "
     "(DatasetConfig, a dict: the manifest's calibration record)"),
]  # fmt: skip


@pytest.fixture(scope="module")
def made(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two scenes of the ``flawed`` family, made without a flaw."""
    source = PluginSource("flawed", "bpb-flawed", "1.2", "flawed_family")
    registry = make_registry([(support.flawed_family, source)])
    out = tmp_path_factory.mktemp("flawed") / "data"
    return generate_dataset(out, 2, (1.0,), 0, family="flawed", workers=1, images=False,
                            registry=registry)  # fmt: skip


@pytest.mark.parametrize(("flaw", "said"), FLAWS)
def test_bpb_generate_is_one_line_naming_the_family_plugin_and_exit_3(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, made: Path, tmp_path: Path,
    flaw: str, said: str,
) -> None:  # fmt: skip
    _refused(install, run_bpb, monkeypatch, made, tmp_path, flaw, f"{FAMILY}: {said}")


@pytest.mark.parametrize(("flaw", "said"), CALIBRATE_FLAWS)
def test_bpb_generate_calibrate_is_one_line_naming_the_family_plugin_and_exit_3(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, made: Path, tmp_path: Path,
    flaw: str, said: str,
) -> None:  # fmt: skip
    """calibrate_horizon() (in the pool's workers) and apply_calibration() were unchecked:
    "internal error: RuntimeError: ..." naming no plugin, or a swapped pair written as the
    config ("'dict' object has no attribute ...")."""
    config = tmp_path / "quick.json"
    config.write_text('{"calibration": {"samples": 20, "iterations": 4}}')
    extra = ("--calibrate", "--config", str(config))
    _refused(install, run_bpb, monkeypatch, made, tmp_path, flaw, f"{FAMILY}: {said}", extra)


@pytest.mark.parametrize(
    ("flaw", "said", "extra"),
    [
        ("init_in_worker_raise", "creating the scene family 'flawed' raised RuntimeError: "
         "__init__ exploded in a worker", ()),
        # --stable-only starts the pool at once: this process never builds the simulator
        ("simulator_init_raise", "creating the simulator 'flawed-analytic' raised "
         "RuntimeError: simulator __init__ exploded", ("--stable-only",)),
    ],
)  # fmt: skip
def test_a_family_or_simulator_that_cannot_be_created_in_a_worker_is_one_line_not_a_hang(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, made: Path, tmp_path: Path,
    flaw: str, said: str, extra: tuple[str, ...],
) -> None:  # fmt: skip
    """The family's and simulator's constructors in the pool initializer were unchecked: each
    worker died of it and the pool started another, for ever (bpb generate hung)."""
    _refused(install, run_bpb, monkeypatch, made, tmp_path, flaw, said, extra)


def _refused(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, made: Path, tmp_path: Path,
    flaw: str, said: str, extra: tuple[str, ...] = (),
) -> None:  # fmt: skip
    """``bpb generate`` with ``flaw`` over a copy of ``made``: exit 3, one line naming the
    plugin (``said`` after it), and the dataset it was to replace as it was."""
    source = Path(support.flawed_family.__file__).read_text()
    install("bpb-flawed", "1.2", {"flawed_family": source}, {"flawed": "flawed_family"})
    out = shutil.copytree(made, tmp_path / "data")
    before = tree(out)
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    done = run_bpb("generate", "--family", "flawed", "--out", str(out), "--per-horizon", "2",
                   "--horizons", "1", "--workers", "2", "--no-images", "--overwrite",
                   *extra)  # fmt: skip
    assert done.returncode == 3
    assert done.stderr.strip().splitlines() == [
        f"error: {ORIGIN}: {said} (set BPB_DEBUG=1 for a traceback)"
    ]
    assert tree(out) == before
