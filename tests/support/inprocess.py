"""``bpb`` commands run in the test's own process, as the console script runs them.

:func:`bpb` calls :func:`bpb_core.cli.main.main` (which ends in ``sys.exit`` with bpb's exit
code) and returns the exit code with what the command wrote on standard output and standard
error, captured by pytest's ``capfd`` (at the file descriptors, so that a forked worker's lines
are caught too), or for a fixture wider than a test by :func:`streams`. A test checks the same
exit code and the same messages as it would of the ``bpb`` process, without paying a Python
start-up and bpb's imports per command.

What a process would have had of its own is given back after each command: the environment
(``main`` sets the BLAS thread variables), the warning filters and display, the rich consoles
(built again per command, so that ``COLUMNS`` set by the test is their width), and, with
``site``, the ``sys.path`` entry and the modules imported from it. A test's environment for the
command is ``monkeypatch.setenv``, its working folder ``monkeypatch.chdir``.

Tests keep a real process where a process is what they test: signals, kill -9, a lock held by
another process, standard streams without an encoding or with a strict one (``capfd`` replaces
what it cannot encode, so a lone surrogate printed would pass unseen), a fresh interpreter's
imports.
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib
import os
import sys
import tempfile
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Protocol, TextIO

import pytest

from bpb_core.cli import console
from bpb_core.cli.main import main


@dataclasses.dataclass(frozen=True)
class Done:
    """A finished command: its exit code and output (the names of ``CompletedProcess``)."""

    returncode: int
    stdout: str
    stderr: str


class Capture(Protocol):
    """What :func:`bpb` reads a command's output from: ``capfd``, or :func:`streams`."""

    def readouterr(self) -> tuple[str, str]: ...


class _Files:
    """Standard output and standard error as two text files, read and emptied together."""

    def __init__(self, out: TextIO, err: TextIO) -> None:
        self.files = (out, err)

    def readouterr(self) -> tuple[str, str]:
        texts = []
        for file in self.files:
            file.flush()
            file.seek(0)
            texts.append(file.read())
            file.seek(0)
            file.truncate()
        return texts[0], texts[1]


@contextlib.contextmanager
def streams() -> Iterator[Capture]:
    """``sys.stdout`` and ``sys.stderr`` in files of their own for the block, for a module's
    fixture (``capfd`` is a test's); lines written at the file descriptors are not caught."""
    with contextlib.ExitStack() as stack:
        out = stack.enter_context(tempfile.TemporaryFile("w+", encoding="utf-8"))
        err = stack.enter_context(tempfile.TemporaryFile("w+", encoding="utf-8"))
        stack.enter_context(contextlib.redirect_stdout(out))
        stack.enter_context(contextlib.redirect_stderr(err))
        yield _Files(out, err)


def bpb(capfd: Capture | pytest.CaptureFixture[str], *args: str, site: Path | None = None) -> Done:
    """Run ``bpb ARGS`` in this process; with ``site``, a folder of plugin distributions first
    on ``sys.path`` (as ``PYTHONPATH`` puts it before the installed ones)."""
    capfd.readouterr()  # what the test printed before is not the command's
    environment = dict(os.environ)
    imported = set(sys.modules)
    if site is not None:
        sys.path.insert(0, str(site))
        importlib.invalidate_caches()  # importlib.metadata's view of the folder, too
    console.stdout.cache_clear()
    console.stderr.cache_clear()
    try:
        with warnings.catch_warnings():  # main's display of notices; once-only warnings anew
            code = _exit_code(list(args))
    finally:
        os.environ.clear()
        os.environ.update(environment)
        console.stdout.cache_clear()
        console.stderr.cache_clear()
        if site is not None:
            sys.path.remove(str(site))
            _forget_modules_from(site, set(sys.modules) - imported)
            importlib.invalidate_caches()
    out, err = capfd.readouterr()
    return Done(code, out, err)


def _exit_code(argv: list[str]) -> int:
    try:
        main(argv)
    except SystemExit as exit_:
        code = exit_.code
        if code is None:
            return 0
        assert isinstance(code, int), code  # main exits with a number
        return code
    raise AssertionError("bpb_core.cli.main.main returned instead of exiting")


def _forget_modules_from(site: Path, names: set[str]) -> None:
    """Drop the modules a command imported from ``site``: the next command (a process, for the
    user) imports the plugin as it is then, and another test's plugin of the same name is its
    own."""
    root = site.resolve()
    for name in names:
        origin = getattr(sys.modules.get(name), "__file__", None)
        if origin is not None and Path(origin).resolve().is_relative_to(root):
            del sys.modules[name]
