"""A scene family's load_config(), make_scene() (run in the pool's workers) or write_stats()
that raises or returns the wrong type is one line naming the family's plugin and the hook, exit
3, from ``bpb generate``; the dataset it was to overwrite is left as it was.

Before, each came out as "internal error: RuntimeError: ..." naming no plugin, or as an
AttributeError or TypeError from the code that took the value next ("'FinalState' object has no
attribute 'truth'", "'list' object has no attribute 'items'"); write_stats() returning a single
path was read letter by letter (a FileNotFoundError for ``.data.partial/s``), and a path it
never wrote was a FileNotFoundError too.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pytest

import support.flawed_family
from bpb_core.dataset import generate_dataset
from bpb_core.registry import PluginSource, make_registry

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
]  # fmt: skip


@pytest.fixture(scope="module")
def made(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two scenes of the ``flawed`` family, made without a flaw."""
    source = PluginSource("flawed", "bpb-flawed", "1.2", "flawed_family")
    registry = make_registry([(support.flawed_family, source)])
    out = tmp_path_factory.mktemp("flawed") / "data"
    return generate_dataset(out, 2, (1.0,), 0, family="flawed", workers=1, images=False,
                            registry=registry)  # fmt: skip


def _files(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*") if p.is_file()}


@pytest.mark.parametrize(("flaw", "said"), FLAWS)
def test_bpb_generate_is_one_line_naming_the_family_plugin_and_exit_3(
    install: Any, run_bpb: Any, monkeypatch: pytest.MonkeyPatch, made: Path, tmp_path: Path,
    flaw: str, said: str,
) -> None:  # fmt: skip
    source = Path(support.flawed_family.__file__).read_text()
    install("bpb-flawed", "1.2", {"flawed_family": source}, {"flawed": "flawed_family"})
    out = shutil.copytree(made, tmp_path / "data")
    before = _files(out)
    monkeypatch.setenv("BPB_TEST_FLAW", flaw)
    done = run_bpb("generate", "--family", "flawed", "--out", str(out), "--per-horizon", "2",
                   "--horizons", "1", "--workers", "2", "--no-images", "--overwrite")  # fmt: skip
    assert done.returncode == 3
    assert done.stderr.strip().splitlines() == [
        f"error: {ORIGIN}: {FAMILY}: {said} (set BPB_DEBUG=1 for a traceback)"
    ]
    assert _files(out) == before  # the dataset it was to replace is as it was
