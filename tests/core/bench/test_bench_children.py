"""The bench's child processes never outlive it, even when a signal stops it as one starts."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from support.processes import HAS_PROC, ended, group_members, run_group

# A bench's main, stopped by a SIGTERM that arrives while its child starts: the child sends it
# between its fork and its exec, while Popen waits for the exec, the window a busy machine
# widens (bpb bench run's fake client used to be left running, measuring nothing, for ever).
_STOPPED_WHILE_STARTING = """
import os, signal, sys, time
from bpb_core.bench.children import child

def terminated(signum, frame):
    raise SystemExit(128 + signum)

signal.signal(signal.SIGTERM, terminated)
sleeper = [sys.executable, "-c", "import time; time.sleep(300)"]
with child(sleeper, preexec_fn=lambda: os.kill(os.getppid(), signal.SIGTERM)):
    print("not stopped", flush=True)
    time.sleep(300)
"""


@pytest.mark.skipif(not HAS_PROC, reason="lists the process group through /proc")
def test_a_sigterm_while_a_child_starts_stops_the_bench_and_the_child(tmp_path: Path) -> None:
    returncode, out, err, left = _run_in_own_group(tmp_path, _STOPPED_WHILE_STARTING)
    assert returncode == 128 + signal.SIGTERM, err
    assert out == ""  # the held signal is acted on before the block's body runs
    assert left == [], "the child outlived the bench"


def _run_in_own_group(tmp_path: Path, script: str) -> tuple[int, str, str, list[int]]:
    """Run ``script`` in its own process group until it ends: its exit code, stdout, stderr and
    the group's members still running then (killed afterwards)."""
    out, err = tmp_path / "out", tmp_path / "err"
    with out.open("w") as stdout, err.open("w") as stderr:  # files: a leftover holds no pipe
        process = subprocess.Popen(
            [sys.executable, "-c", script], stdout=stdout, stderr=stderr, start_new_session=True
        )
    try:
        returncode = process.wait(timeout=120)
        left = group_members(process.pid)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)
    return returncode, out.read_text(), err.read_text(), left


# A command whose child (a server, a client) runs until it is stopped, like bpb bench run's;
# the child shares its stdout, so that output ends only when both have ended
_PARENT_OF_A_SERVER = """
import os, subprocess, sys, time
server = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(300)"])
print(server.pid, flush=True)
time.sleep(300)
"""


@pytest.mark.skipif(not HAS_PROC, reason="lists the process group through /proc")
def test_a_command_that_times_out_in_a_test_is_killed_with_its_children() -> None:
    """subprocess.run's timeout killed the bench command alone: its server and client ran on."""
    with pytest.raises(subprocess.TimeoutExpired) as timed_out:
        run_group([sys.executable, "-c", _PARENT_OF_A_SERVER], timeout=10)
    server = int(timed_out.value.stdout)
    gone = ended(server, within=30)  # SIGKILL is delivered asynchronously
    if not gone:  # not to leave it running when the test fails
        os.kill(server, signal.SIGKILL)
    assert gone, "the command's child outlived it"


# bpb bench startup's and bench generate --memory's measurement, stopped as above: the patched
# Popen (the standard library's, not ours) gives every child the SIGTERM-sending preexec_fn, and
# the child then sleeps before its exec, so that one left behind is still there to be seen
_MEASUREMENT_STOPPED_WHILE_STARTING = """
import os, signal, subprocess, time

def terminated(signum, frame):
    raise SystemExit(128 + signum)

def stop_the_bench():
    os.kill(os.getppid(), signal.SIGTERM)
    time.sleep(5)

class Starting(subprocess.Popen):
    def __init__(self, args, **popen):
        super().__init__(args, **popen, preexec_fn=stop_the_bench)

subprocess.Popen = Starting
signal.signal(signal.SIGTERM, terminated)
from bpb_core.bench.{module} import {function}
{function}({args})
print("not stopped", flush=True)
"""


@pytest.mark.skipif(not HAS_PROC, reason="lists the process group through /proc")
@pytest.mark.parametrize(
    ("module", "function", "args"),
    [("startup", "measure_startup", "1"), ("generate", "measure_memory", "1, 1")],
)
def test_bench_startup_and_memory_leave_no_child_when_stopped_as_one_starts(
    tmp_path: Path, module: str, function: str, args: str
) -> None:
    """They ran their children with subprocess.run, whose Popen left the child running."""
    script = _MEASUREMENT_STOPPED_WHILE_STARTING.format(module=module, function=function, args=args)
    returncode, out, err, left = _run_in_own_group(tmp_path, script)
    assert returncode == 128 + signal.SIGTERM, err
    assert out == ""
    assert left == [], "the measured command outlived the bench"
