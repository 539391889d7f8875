"""``bpb bench run``: runner overhead and memory, measured from the fake server's side.

Throughput: the fake OpenAI server answers every request after ``latency`` seconds. In one
session, a bare ``litellm.acompletion`` loop and ``bpb run`` (through the litellm adapter) each
send the same number of requests with the same concurrency; the server labels arrivals by phase.
A phase's rate is ``count / (last arrival - first arrival + latency)``: requests divided by the
time from the first arrival until the last reply was due; the ideal is ``concurrency / latency``.
Process start-up and litellm's import come before the first arrival and do not count.

Both clients ask what ``bpb run`` asks by default: every default task of the dataset's scene
family (image input when the family has images, else state). Memory: the peak resident set of
a ``bpb run`` subprocess making ``tasks x scenes`` calls against the server with no latency.
Each client's peak is its own (:mod:`bpb_core.bench.peak`), not the bench's that ``wait4``
would add. :func:`bench_dataset` makes (or reuses) the dataset.
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
import urllib.request
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bpb_core.bench import peak
from bpb_core.bench.children import child
from bpb_core.bench.run_bare import CALL_TIMEOUT, input_mode

_DUMMY_KEY = "sk-bench-local-not-a-secret"
_BARE = "bpb_core.bench.run_bare:main"
_BPB = "bpb_core.cli.main:main"


@dataclass(frozen=True)
class Phase:
    """One measured client."""

    name: str
    requests: int
    seconds: float
    rate: float
    peak_rss_mb: float
    exit_code: int
    error: str = ""
    """The last line a failed client wrote to stderr (empty when it succeeded)."""


class _Server:
    def __init__(self, process: subprocess.Popen[str]) -> None:
        assert process.stdout is not None
        self.port = int(process.stdout.readline().split()[1])
        self.url = f"http://127.0.0.1:{self.port}"

    def phase(self, name: str) -> None:
        body = json.dumps({"name": name}).encode()
        request = urllib.request.Request(f"{self.url}/phase", body, {"Content-Type": "json"})
        urllib.request.urlopen(request, timeout=10).read()

    def stats(self) -> dict[str, Any]:
        with urllib.request.urlopen(f"{self.url}/stats", timeout=10) as response:
            data: dict[str, Any] = json.loads(response.read())
        return data


@contextlib.contextmanager
def _server(latency: float) -> Iterator[_Server]:
    """The fake server, once it listens; stopped when the block ends (also when a signal
    stops the bench while it starts)."""
    args = [sys.executable, "-m", "bpb_core.testing.fakeserver", "--latency", str(latency)]
    with child(args, stdout=subprocess.PIPE, text=True) as process:
        yield _Server(process)


def run_client(entry: str, args: list[str]) -> tuple[int, float, str]:
    """Run ``entry`` (``module:function``) with ``args`` in a child process; return its exit
    code, its own peak RSS in MiB and, when it failed, the last line of its stderr (kept in a
    file: an unread pipe would block a chatty child)."""
    env = {**os.environ, "OPENAI_API_KEY": _DUMMY_KEY}
    with (
        tempfile.TemporaryDirectory(prefix="bpb-bench-peak-") as tmp,
        tempfile.TemporaryFile("w+", encoding="utf-8", errors="replace") as err,
    ):
        report = Path(tmp) / "peak"
        args = peak.command(report, entry, args)
        with child(args, env=env, stdout=subprocess.DEVNULL, stderr=err) as process:
            # interrupted, the client is stopped: it must not outlive the bench
            _, status, usage = os.wait4(process.pid, 0)
            process.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        lines = [line.strip() for line in err if line.strip()] if process.returncode else []
        rss = peak.peak_mib(report, usage.ru_maxrss)
    return process.returncode, rss, lines[-1] if lines else ""


def bench_dataset(
    work: Path, per_horizon: int, on_generate: Callable[[Path, int], None] | None = None
) -> Path:
    """A dataset with images of ``per_horizon`` scenes per horizon (1-5 s) under ``work``:
    one made earlier with at least as many scenes (runs take the first N per horizon), else a
    new one ``bench-run-data-N`` (``on_generate`` is told its path and scene count first)."""
    from bpb_core.dataset import generate_dataset

    for found in sorted(work.glob("bench-run-data-*")):
        size = found.name.rsplit("-", 1)[-1]
        if size.isdigit() and int(size) >= per_horizon and (found / "dataset.json").exists():
            return found
    data = work / f"bench-run-data-{per_horizon}"
    if on_generate is not None:
        on_generate(data, 5 * per_horizon)
    return generate_dataset(data, per_horizon, [1, 2, 3, 4, 5], seed=0)


def planned_calls(data: Path, scenes_per_horizon: int) -> int:
    """Calls of a default ``bpb run`` on the first ``scenes_per_horizon`` scenes per horizon."""
    from bpb_core.registry import make_registry
    from bpb_core.runner.asking import asking
    from bpb_core.runner.options import RunOptions

    ask = asking(data, RunOptions(limit=scenes_per_horizon), make_registry())
    return len(ask.tasks) * len(ask.scenes)


def _bpb(data: Path, api_base: str, out: Path, concurrency: int, limit: int) -> list[str]:
    return [
        "run",
        "--data",
        str(data),
        "--adapter",
        "litellm:openai/fake-model",
        "--api-base",
        api_base,
        "--out",
        str(out),
        "--concurrency",
        str(concurrency),
        "--limit",
        str(limit),
        "--timeout",
        str(CALL_TIMEOUT),
        "--input-mode",
        input_mode(data),
    ]


def _measure(server: _Server, name: str, entry: str, args: list[str], latency: float) -> Phase:
    server.phase(name)
    code, rss, error = run_client(entry, args)
    info = server.stats()["phases"].get(name, {"count": 0, "first": 0.0, "last": 0.0})
    span = info["last"] - info["first"] + latency
    rate = info["count"] / span if span > 0 else 0.0
    return Phase(name, info["count"], span, rate, rss, code, error)


def _combine(name: str, phases: list[Phase]) -> Phase:
    requests = sum(p.requests for p in phases)
    seconds = sum(p.seconds for p in phases)
    return Phase(
        name,
        requests,
        seconds,
        requests / seconds if seconds > 0 else 0.0,
        max(p.peak_rss_mb for p in phases),
        max((p.exit_code for p in phases), key=abs),
        next((p.error for p in phases if p.exit_code), ""),
    )


def bench_throughput(
    data: Path,
    concurrency: int = 64,
    latency: float = 1.0,
    scenes_per_horizon: int = 43,
    rounds: int = 2,
) -> tuple[Phase, Phase]:
    """Requests per second of a bare litellm loop and of ``bpb run`` against one server.

    The two clients alternate for ``rounds`` rounds (bare, bpb, bare, bpb, ...) so drifting
    machine load hits both alike; each result pools its rounds (total requests / total time).
    """
    calls = planned_calls(data, scenes_per_horizon)
    bare: list[Phase] = []
    ours: list[Phase] = []
    with _server(latency) as server:
        api_base = f"{server.url}/v1"
        for round_no in range(rounds):
            bare_args = [api_base, str(calls), str(concurrency), str(data)]
            bare.append(_measure(server, f"bare{round_no}", _BARE, bare_args, latency))
            with tempfile.TemporaryDirectory() as tmp:
                args = _bpb(data, api_base, Path(tmp), concurrency, scenes_per_horizon)
                ours.append(_measure(server, f"bpb{round_no}", _BPB, args, latency))
    return _combine("bare litellm loop", bare), _combine("bpb run", ours)


def bench_memory(data: Path, scenes_per_horizon: int, concurrency: int = 64) -> Phase:
    """Peak RSS of a ``bpb run`` of ``tasks x scenes`` calls against a zero-latency server."""
    with _server(0.0) as server, tempfile.TemporaryDirectory() as tmp:
        started = time.perf_counter()
        args = _bpb(data, f"{server.url}/v1", Path(tmp), concurrency, scenes_per_horizon)
        phase = _measure(server, "memory", _BPB, args, 0.0)
        return Phase(
            "bpb run (memory)",
            phase.requests,
            time.perf_counter() - started,
            phase.rate,
            phase.peak_rss_mb,
            phase.exit_code,
            phase.error,
        )
