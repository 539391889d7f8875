"""``bpb simulate``: print each scene's ground truth (final.json content) as one JSON line."""

from __future__ import annotations

import codecs
import io
import os
import sys
from typing import Any

import click

from bpb_core.errors import NO_ROOM, WriteRefused, write_refused


class _Named(click.Path):
    """A path argument taken as given (shell completion as for paths): the library checks each
    once, naming the one that is missing, so ten thousand scene files are not stat'ed twice."""

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        return value


class _ManyPaths(click.Command):
    """A command taking many paths: click's parser takes each argument off the front of a
    list, moving the rest of the list every time, so its time grew with the square of the
    number of paths (about a microsecond per scene at 10,000 paths, five at 50,000). Each
    long run of plain arguments reaches the parser as its first argument (it may be an
    option's value) and one stand-in for the others, which are put back in ``paths`` after."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        folded, runs = _fold(args)
        rest = super().parse_args(ctx, folded)
        if runs:
            paths: list[str] = []
            for name in ctx.params.get("paths") or ():
                run = runs.get(name)
                if run is None:
                    paths.append(name)
                else:
                    paths += run
            ctx.params["paths"] = tuple(paths)
        return rest


def _fold(args: list[str]) -> tuple[list[str], dict[str, list[str]]]:
    """``args`` with each run of three or more arguments that are not options (up to a
    ``--``, after which click takes the rest at once) cut to its first and a stand-in for the
    others, and the runs by stand-in: a stand-in holds a NUL, which no argument can."""
    folded: list[str] = []
    runs: dict[str, list[str]] = {}
    at, end = 0, len(args)
    while at < end:
        if args[at] == "--":
            folded.extend(args[at:])
            break
        stop = at
        while stop < end and not args[stop].startswith("-"):
            stop += 1
        if stop - at > 2:
            stand_in = f"\0{len(runs)}"
            runs[stand_in] = args[at + 1 : stop]
            folded += [args[at], stand_in]
        else:
            folded.extend(args[at : max(stop, at + 1)])
        at = max(stop, at + 1)
    return folded, runs


@click.command("simulate", cls=_ManyPaths)
@click.argument("paths", nargs=-1, required=True, type=_Named())
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
    horizon: float | None,
    simulator: str | None,
    dt: float | None,
    precision: str | None,
    engine: str | None,
    stability: bool,
    workers: int,
) -> None:
    """Simulate init.json files, scene folders or dataset folders, in input order."""
    from bpb_core.simulate import simulate_blocks

    options: dict[str, Any] = {}
    if dt is not None:
        options["dt"] = dt
    if precision is not None:
        options["precision"] = precision
    if engine is not None:
        options["engine"] = engine
    out = _Output()
    for block in simulate_blocks(  # up to 512 lines each: not one write per line
        paths,
        horizon=horizon,
        simulator=simulator,
        stability=stability,
        options=options,
        workers=workers,
        names=FLAGS,
    ):
        out.write(block)  # the lines before a bad file are written before its error


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
        encoding = getattr(sys.stdout, "encoding", None) or "utf-8"  # None: io.StringIO
        self.encoding = None if codecs.lookup(encoding).name == "utf-8" else encoding
        # the lines are UTF-8: else transcoded
        self.errors = getattr(sys.stdout, "errors", None) or "strict"

    def write(self, block: bytes) -> None:
        """Write ``block``'s lines (UTF-8, each ended by a newline) in standard output's
        encoding."""
        count = block.count(b"\n")
        if self.fd is None:
            sys.stdout.write(block.decode())
        else:
            if self.encoding is not None:
                block = block.decode().encode(self.encoding, self.errors)
            self._write_all(self.fd, block)
        self.lines += count

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
