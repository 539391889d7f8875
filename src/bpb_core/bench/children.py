"""Child processes of a benchmark that never outlive it, even when it is stopped by a signal.

``subprocess.Popen`` forks, then waits for the child's exec; a SIGTERM or Ctrl-C whose handler
raises in that wait leaves ``Popen`` with an exception and the child running, with no process
object to stop it (a window of milliseconds that a busy machine widens to tens). :func:`child`
holds the two signals while ``Popen`` runs and delivers a held one only once the process is in
the ``try`` that stops it; :func:`run_child` is ``subprocess.run`` through it.
"""

from __future__ import annotations

import contextlib
import signal
import subprocess
import threading
from collections.abc import Iterator
from typing import Any

_HELD = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def child(args: list[str], **popen: Any) -> Iterator[subprocess.Popen[Any]]:
    """``subprocess.Popen(args, **popen)`` for the block; killed and reaped when the block
    ends, however it ends. A SIGINT or SIGTERM that arrives while it starts is acted on as the
    block begins (after the process is in hand), the way it would have been acted on anyway."""
    with _signals_held() as held:
        process = subprocess.Popen(args, **popen)
    try:
        for signum in held:
            signal.raise_signal(signum)  # the handler put back runs now, inside this try
        yield process
    finally:
        process.kill()
        with process:  # closes its pipes and reaps it
            pass


def run_child(args: list[str], **popen: Any) -> subprocess.CompletedProcess[Any]:
    """``subprocess.run(args, check=True, **popen)`` started by :func:`child`: the process is
    waited for, and killed if the bench is stopped meanwhile or as it starts.

    Raises:
        subprocess.CalledProcessError: It exited non-zero (its output attached).
    """
    with child(args, **popen) as process:
        stdout, stderr = process.communicate()
    if process.returncode:
        raise subprocess.CalledProcessError(process.returncode, args, stdout, stderr)
    return subprocess.CompletedProcess(args, process.returncode, stdout, stderr)


@contextlib.contextmanager
def _signals_held() -> Iterator[list[int]]:
    """Record SIGINT and SIGTERM instead of acting on them for the block (main thread only:
    other threads cannot set handlers, and signals are handled in the main thread anyway)."""
    held: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield held
        return
    before = {signum: signal.signal(signum, lambda s, _: held.append(s)) for signum in _HELD}
    try:
        yield held
    finally:
        for signum, handler in before.items():  # None: not set from Python, the default
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
