"""Fixture of the ``bpb bench`` tests: run a benchmark through the real ``bpb`` console script."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest

from support.processes import run_group

BPB = str(Path(sys.executable).with_name("bpb"))


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
def bench() -> BenchFn:
    """``bench("sim", "--scenes", "2", env={...})`` runs ``bpb bench sim --scenes 2`` with wide
    tables (COLUMNS=200) and returns a :class:`BenchRun`. ``timeout`` only bounds a hang, below
    pytest's 600 s: a benchmark of three litellm clients took 93 s on a loaded 2-core CI
    machine; a command that times out is killed with its whole process group."""

    def _run(
        *args: str | Path, env: Mapping[str, str] | None = None, timeout: float = 480
    ) -> BenchRun:
        environ = {**(env if env is not None else os.environ), "COLUMNS": "200"}
        done = run_group([BPB, "bench", *map(str, args)], timeout, env=environ)
        return BenchRun(done.returncode, done.stdout, done.stderr)

    return _run
