"""``bpb simulate``: print each scene's ground truth (final.json content) as one JSON line."""

from __future__ import annotations

import io
import os
import sys
from collections.abc import Iterable
from typing import Any

import click

from bpb_core.errors import NO_ROOM, BadInput, WriteRefused, write_refused


@click.command("simulate")
@click.argument("paths", nargs=-1, type=click.Path())
@click.option(
    "--from-file",
    "from_file",
    type=click.Path(allow_dash=True),
    default=None,
    help="Also simulate the paths in FILE, one a line ('-': standard input).",
)
@click.option("--horizon", type=float, default=None, help="Override each scene's own horizon (s).")
@click.option(
    "--simulator",
    "simulator",
    default=None,
    help="Simulator, optionally with options as in a dataset config (pymunk:dt=0.0005; a flag "
    "such as --dt wins) [default: the one the dataset was made with, with the options its config "
    "gives it; the default family's for loose scene files].",
)
@click.option(
    "--dt",
    type=float,
    default=None,
    help="Time step (s) of fixed-step simulators; one above a scene's stability bound is an error "
    "naming the bound.",
)
@click.option(
    "--precision", default=None, help="analytic only: 'float64' (default) or digits for mpmath."
)
@click.option(
    "--engine",
    default=None,
    help="analytic only: 'auto' (compiled kernel when installed), 'kernel' or 'python'.",
)
@click.option("--stability", is_flag=True, help="Add the stability annotation (slower).")
@click.option(
    "--workers",
    default=0,
    show_default=True,
    help="Processes (at most 4 per core); 0 = all cores for 256+ scenes, 1 = none.",
)
def simulate(
    paths: tuple[str, ...],
    from_file: str | None,
    horizon: float | None,
    simulator: str | None,
    dt: float | None,
    precision: str | None,
    engine: str | None,
    stability: bool,
    workers: int,
) -> None:
    """Simulate init.json files, scene folders or dataset folders, in input order.

    PATHS may include '-': the paths on standard input, one a line (as --from-file -).
    """
    from bpb_core.simulate import simulate_lines

    named = _named_paths(paths, from_file)
    if not named:
        raise BadInput("no scene paths given (arguments, --from-file FILE, or - for stdin)")
    given = {"dt": dt, "precision": precision, "engine": engine}
    options: dict[str, Any] = {k: v for k, v in given.items() if v is not None}
    lines = simulate_lines(
        named,
        horizon=horizon,
        simulator=simulator,
        stability=stability,
        options=options,
        workers=workers,
        names=FLAGS,
    )
    out = _Output()
    try:
        for line in lines:  # written as they come: the lines before a bad file precede its error
            out.write(line)
    except BrokenPipeError:  # the reader left (`bpb simulate ... | head -1`): stop quietly
        raise click.exceptions.Exit(141) from None


def _named_paths(paths: tuple[str, ...], from_file: str | None) -> list[str]:
    """``paths`` with each ``-`` replaced by the paths on standard input, then those in
    ``from_file`` (``-``: standard input), one a line (blank lines skipped)."""
    named: list[str] = []
    for path in paths:
        named += _listed(sys.stdin) if path == "-" else [path]
    if from_file == "-":
        named += _listed(sys.stdin)
    elif from_file is not None:
        try:
            with open(from_file, encoding="utf-8") as file:
                named += _listed(file)
        except OSError as exc:
            raise BadInput(f"--from-file {from_file}: cannot read: {exc.strerror or exc}") from None
    return named


def _listed(lines: Iterable[str]) -> list[str]:
    return [name for line in lines if (name := line.rstrip("\r\n"))]


FLAGS = {"dt": "--dt", "precision": "--precision", "engine": "--engine"}
"""The simulator options these flags set, for messages (``--dt: 0.1 s is above ...``)."""


class _Output:
    """Standard output, written straight to its file descriptor so that a write the system
    refuses (a full disk, a file size limit) can say how many lines reached the file whole:
    the user knows which scenes are done and which to simulate again."""

    def __init__(self) -> None:
        self.lines = 0  # whole lines written so far
        try:
            sys.stdout.flush()
            self.fd: int | None = sys.stdout.fileno()
        except (AttributeError, ValueError, io.UnsupportedOperation):
            self.fd = None  # a stream with no file behind it (click's CliRunner)
        self.encoding = getattr(sys.stdout, "encoding", None) or "utf-8"  # None: io.StringIO
        self.errors = getattr(sys.stdout, "errors", None) or "strict"

    def write(self, line: str) -> None:
        """Write ``line`` and a newline, in standard output's encoding."""
        if self.fd is None:
            sys.stdout.write(f"{line}\n")
        else:
            self._write_all(self.fd, f"{line}\n".encode(self.encoding, self.errors))
        self.lines += 1

    def _write_all(self, fd: int, data: bytes) -> None:
        left = memoryview(data)
        while left:
            try:
                left = left[os.write(fd, left) :]
            except OSError as exc:  # others (a reader gone: EPIPE) leave as before
                if exc.errno not in NO_ROOM:
                    raise
                raise self._refused(fd, exc, data[: len(data) - len(left)]) from None

    def _refused(self, fd: int, exc: OSError, landed: bytes) -> WriteRefused:
        whole = self.lines + landed.count(b"\n")
        cut = " and the start of the next" if landed and not landed.endswith(b"\n") else ""
        return WriteRefused(
            f"{write_refused(_name(fd), exc)}; it holds the first {whole} lines whole{cut} "
            "(one a scene, in input order): make room, then simulate the rest"
        )


def _name(fd: int) -> str:
    """The file standard output goes to, where the system tells (Linux), for messages."""
    try:
        target = os.readlink(f"/proc/self/fd/{fd}")
    except OSError:
        return "standard output"
    return target if target.startswith("/") else "standard output"
