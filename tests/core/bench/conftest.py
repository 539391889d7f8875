"""Fixture of the ``bpb bench sim`` tests: the command run in-process, through ``main``."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from bpb_core.cli import console
from bpb_core.cli.main import main


@dataclass(frozen=True)
class BenchRun:
    """A finished ``bpb bench ...``: exit code, output and the cells of its table rows."""

    returncode: int
    stdout: str
    stderr: str

    @property
    def rows(self) -> list[list[str]]:
        """Body rows of every table printed, as stripped cells."""
        return [
            [cell.strip() for cell in line.strip().strip("│").split("│")]
            for line in self.stdout.splitlines()
            if line.startswith("│")
        ]

    def row(self, first: str) -> list[str]:
        """The cells after the first of the one row whose first cell is ``first``."""
        (found,) = [r[1:] for r in self.rows if r[0] == first]
        return found


BenchFn = Callable[..., BenchRun]


@pytest.fixture
def bench(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> Iterator[BenchFn]:
    """``bench("sim", "--scenes", "2")`` runs ``bpb bench sim --scenes 2`` in this process with
    wide tables (COLUMNS=200) and returns a :class:`BenchRun`."""
    monkeypatch.setenv("COLUMNS", "200")

    def _run(*args: str | Path) -> BenchRun:
        capsys.readouterr()
        console.stdout.cache_clear()  # built for this test's streams and width
        console.stderr.cache_clear()
        with pytest.raises(SystemExit) as ended:
            main(["bench", *map(str, args)])
        out, err = capsys.readouterr()
        code = ended.value.code
        return BenchRun(code if isinstance(code, int) else 0, out, err)

    yield _run
    console.stdout.cache_clear()
    console.stderr.cache_clear()
