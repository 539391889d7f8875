"""A process's children and signal dispositions, read from /proc (Linux), for the tests that
send a real Ctrl-C (SIGINT) to a ``bpb`` command and its pool."""

from __future__ import annotations

import signal
import time
from pathlib import Path

HAS_PROC = Path("/proc/self/task").is_dir()


def children(pid: int) -> list[int]:
    """The child processes of ``pid``."""
    return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]


def ignores_sigint(pid: int) -> bool:
    """Whether process ``pid`` ignores SIGINT (its SigIgn mask)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    (mask,) = [line.split()[1] for line in status.splitlines() if line.startswith("SigIgn:")]
    return bool(int(mask, 16) & (1 << (signal.SIGINT - 1)))


def settled_workers(pid: int, count: int, deadline: float) -> list[int]:
    """``pid``'s children once there are ``count`` of them (or ``deadline`` has passed), after
    waiting up to 0.5 s more for each to ignore SIGINT: one that gets it between its fork and its
    pool initializer still dies of it (a window of milliseconds, not what the tests are about)."""
    while time.monotonic() < deadline and len(children(pid)) < count:
        time.sleep(0.02)
    workers = children(pid)
    started = time.monotonic()
    while time.monotonic() < started + 0.5 and not all(map(ignores_sigint, workers)):
        time.sleep(0.01)
    return workers


def group_members(pgid: int) -> list[int]:
    """The processes (zombies aside) in process group ``pgid``: a command started with
    ``start_new_session=True`` leaves none of its children behind when this is empty after it."""
    members = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            state, _, group = stat.read_text().rsplit(")", 1)[1].split()[:3]
        except (OSError, ValueError):
            continue  # ended while listed
        if int(group) == pgid and state != "Z":
            members.append(int(stat.parent.name))
    return members
