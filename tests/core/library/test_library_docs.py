"""docs/library.md is run as a doctest: every example a user copies must work as written."""

from __future__ import annotations

import doctest
from pathlib import Path

import pytest

from support.paths import DOCS


@pytest.mark.slow
def test_library_page_examples_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("BPB_CACHE_DIR", str(tmp_path / "cache"))  # where exports unpack
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    result = doctest.testfile(str(DOCS / "library.md"), module_relative=False, optionflags=flags)
    assert result.attempted >= 20
    assert result.failed == 0
