"""A process's children and signal dispositions, read from /proc (Linux), for the tests that
send a real Ctrl-C (SIGINT) to a ``bpb`` command and its pool."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

HAS_PROC = Path("/proc/self/task").is_dir()


def children(pid: int) -> list[int]:
    """The child processes of ``pid``."""
    return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]


def _signal_mask(pid: int, field: str, signum: int) -> bool:
    """Whether ``signum`` is in process ``pid``'s ``field`` mask of /proc/PID/status (False
    once it has ended)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    (mask,) = [line.split()[1] for line in status.splitlines() if line.startswith(f"{field}:")]
    return bool(int(mask, 16) & (1 << (signum - 1)))


def ignores_sigint(pid: int) -> bool:
    """Whether process ``pid`` ignores SIGINT (its SigIgn mask)."""
    return _signal_mask(pid, "SigIgn", signal.SIGINT)


def catches_sigterm(pid: int) -> bool:
    """Whether process ``pid`` has a handler of its own for SIGTERM (its SigCgt mask)."""
    return _signal_mask(pid, "SigCgt", signal.SIGTERM)


def settled_workers(pid: int, count: int, deadline: float) -> list[int]:
    """``pid``'s children once there are ``count`` of them and each ignores SIGINT (or once
    ``deadline`` has passed): the tests that use it are about workers at work (the start-up
    window is :func:`ctrl_c_at_worker_start`'s). A worker that never comes to ignore it is
    returned at the deadline."""
    while time.monotonic() < deadline and len(children(pid)) < count:
        time.sleep(0.02)
    workers = children(pid)
    while time.monotonic() < deadline and not all(map(ignores_sigint, workers)):
        time.sleep(0.01)
    return workers


def as_in_a_terminal() -> None:
    """``preexec_fn`` giving the command SIGINT at its default, as a shell gives a foreground
    command: a suite started in the background without job control (``pytest &`` in a script,
    as CI may run it) has SIGINT ignored, its commands inherit that, and Ctrl-C would never
    reach them."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def ended(pid: int, within: float) -> bool:
    """Whether process ``pid`` has ended (or is a zombie) within ``within`` seconds: a signal
    is delivered asynchronously, and a busy machine can run the target on for a while."""
    deadline = time.monotonic() + within
    while running(pid) and time.monotonic() < deadline:
        time.sleep(0.02)
    return not running(pid)


def ctrl_c(
    process: subprocess.Popen[str],
    workers: int,
    deadline: float,
    before: Callable[[], None] = lambda: None,
) -> str:
    """What a terminal's Ctrl-C does to ``process`` (started in its own session) and its pool of
    ``workers``, once ``before()`` has returned: SIGINT to each settled worker first, so that one
    that does not ignore it has the time to print its traceback, then to the whole group.
    Returns its stderr; the group is killed in any case (no pool left behind by a failure)."""

    def workers_first() -> None:
        before()
        for pid in settled_workers(process.pid, workers, deadline):
            os.kill(pid, signal.SIGINT)
        time.sleep(0.5)

    return _group_ctrl_c(process, workers_first)


def _group_ctrl_c(process: subprocess.Popen[str], prepare: Callable[[], None]) -> str:
    """SIGINT to ``process``'s group once ``prepare()`` has returned; its stderr. The group is
    killed in any case (no pool left behind by a failure)."""
    return signal_the_group(process, signal.SIGINT, prepare)


def signal_the_group(
    process: subprocess.Popen[str], signum: int, prepare: Callable[[], None] = lambda: None
) -> str:
    """``signum`` to ``process``'s group (started in its own session) once ``prepare()`` has
    returned, as a terminal's Ctrl-C (SIGINT) or ``kill -TERM -PGID`` (a cancelled CI job)
    sends it; its stderr. The group is killed in any case (no pool left behind by a failure)."""
    try:
        prepare()
        os.killpg(process.pid, signum)
        _, stderr = process.communicate(timeout=60)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)
    return stderr


def _state_and_group(pid: int) -> tuple[str, int] | None:
    """Process ``pid``'s state letter and process group, None once it has gone."""
    try:
        state, _, group = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[:3]
    except (OSError, ValueError):
        return None
    return state, int(group)


def running(pid: int) -> bool:
    """Whether process ``pid`` exists and is not a zombie (ended, not yet reaped)."""
    found = _state_and_group(pid)
    return found is not None and found[0] != "Z"


def group_members(pgid: int) -> list[int]:
    """The running processes of process group ``pgid``: a command started with
    ``start_new_session=True`` leaves none of its children behind when this is empty after it."""
    pids = [int(p.name) for p in Path("/proc").iterdir() if p.name.isdigit()]
    return [pid for pid in pids if running(pid) and (_state_and_group(pid) or ("", 0))[1] == pgid]


def run_group(
    args: Sequence[str], timeout: float, **popen: Any
) -> subprocess.CompletedProcess[str]:
    """``subprocess.run(args, capture_output=True, text=True, timeout=timeout)`` in a session
    of its own, whose whole process group is killed when it times out or the test is stopped:
    ``subprocess.run`` kills the command alone, and its children (a server, a client, a pool)
    were left running for ever."""
    with subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          start_new_session=True, **popen) as process:  # fmt: skip
        try:
            stdout, stderr = process.communicate(timeout=timeout)
        except BaseException as stopped:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
            if isinstance(stopped, subprocess.TimeoutExpired):  # what it said, as run() does
                stopped.output, stopped.stderr = process.communicate()
            raise
    return subprocess.CompletedProcess(args, process.returncode, stdout, stderr)


SLOW_START = """\
import multiprocessing.util, os, pathlib, time

class _Start:
    pass

def _late(start):
    # in the forked worker, before its pool initializer: say so, then linger
    pathlib.Path(os.environ["BPB_TEST_STARTED"], str(os.getpid())).touch()
    time.sleep(1.0)

_START = _Start()
multiprocessing.util.register_after_fork(_START, _late)
"""


def ctrl_c_at_worker_start(args: Sequence[str], workers: int, scratch: Path) -> tuple[int, str]:
    """Run ``args`` (a ``bpb`` command with a pool of ``workers``) in a session of its own and
    send Ctrl-C to its group while every worker is between its fork and its pool initializer (a
    window of milliseconds, held open for a second by a ``sitecustomize`` of ``scratch``).
    Returns the exit code and stderr; the group is killed in any case."""
    started = scratch / "started"
    started.mkdir()
    (scratch / "sitecustomize.py").write_text(SLOW_START)
    path = os.pathsep.join(filter(None, [str(scratch), os.environ.get("PYTHONPATH")]))
    env = {**os.environ, "PYTHONPATH": path, "BPB_TEST_STARTED": str(started)}
    process = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                               start_new_session=True, preexec_fn=as_in_a_terminal,
                               env=env)  # fmt: skip

    def workers_held() -> None:
        deadline = time.monotonic() + 120
        while len(list(started.iterdir())) < workers and time.monotonic() < deadline:
            time.sleep(0.01)

    stderr = _group_ctrl_c(process, workers_held)
    return process.returncode, stderr
