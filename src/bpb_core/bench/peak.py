"""A process's own peak resident set, without the one it inherits when it is started.

On Linux, ``exec`` records the high-water mark of the address space it replaces in the new
program's ``ru_maxrss``: a child of a process holding 400 MB (forked, or started with vfork or
posix_spawn, which run on the parent's memory until the exec) reports at least 400 MB from
``wait4`` and ``getrusage`` even for ``python -c pass``. ``VmHWM`` in ``/proc/self/status`` is
the high-water mark of the process's own address space alone (the interpreter included, about
10 MB).

``python -m bpb_core.bench.peak REPORT MODULE:FUNCTION [ARGS...]`` calls ``FUNCTION`` of
``MODULE`` with ``sys.argv`` set to ``[MODULE, *ARGS]`` and, as the process exits, writes its
``VmHWM`` in KiB to ``REPORT``. Where there is no ``/proc`` (not Linux) it writes nothing and
:func:`peak_mib` falls back to the ``wait4`` figure, with its inherited floor.
"""

from __future__ import annotations

import atexit
import importlib
import sys
from pathlib import Path


def own_peak_kib() -> int | None:
    """``VmHWM`` of this process in KiB, or None where ``/proc/self/status`` has none."""
    try:
        status = Path("/proc/self/status").read_text(encoding="ascii", errors="replace")
    except OSError:
        return None
    for line in status.splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
    return None


def command(report: Path, entry: str, args: list[str]) -> list[str]:
    """The command that runs ``entry`` (``module:function``) with ``args`` and writes its own
    peak RSS to ``report``."""
    return [sys.executable, "-m", "bpb_core.bench.peak", str(report), entry, *args]


def peak_mib(report: Path, wait4_kib: int) -> float:
    """The peak RSS in MiB that the process of :func:`command` wrote to ``report``, else the
    ``ru_maxrss`` that ``wait4`` gave for it (``wait4_kib``)."""
    try:
        return int(report.read_text(encoding="ascii")) / 1024
    except (OSError, ValueError):
        return wait4_kib / 1024


def _write(report: str) -> None:
    kib = own_peak_kib()
    if kib is not None:
        Path(report).write_text(str(kib), encoding="ascii")


def main() -> None:
    """Command-line entry: REPORT MODULE:FUNCTION [ARGS...]."""
    report, entry, *args = sys.argv[1:]
    module, _, function = entry.partition(":")
    atexit.register(_write, report)  # registered first, so it runs last
    sys.argv = [module, *args]
    getattr(importlib.import_module(module), function)()


if __name__ == "__main__":
    main()
