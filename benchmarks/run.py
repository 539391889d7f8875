"""``bpb run``'s request rate against a bare litellm loop, and its peak memory, measured from
the side of the fake server (``bpb_testing.fakeserver``, ``pip install -e plugins/bpb-testing``).

Usage: ``python benchmarks/run.py [--concurrency 64] [--latency 1.0] [--throughput-scenes 43]
[--memory-scenes 200] [--rounds 2] [--work .bpb-bench]``.

Throughput: the fake server answers every request after ``--latency`` seconds. A bare
``litellm.acompletion`` loop and ``bpb run`` (through the litellm adapter) each send the same
requests (every default task of the dataset's family about the first scenes, with the image
when the family has one) with the same concurrency, alternating for ``--rounds`` rounds; the
server labels arrivals by phase. A phase's rate is its requests over the time from the first
arrival to when the last reply was due; the ideal is ``concurrency / latency``. Process start-up
and imports come before the first arrival and do not count. Memory: the peak resident set
(``VmHWM``, the client's own) of a ``bpb run`` against the server with no latency. The dataset
is generated under ``--work`` once and reused. Exits 1 when a client failed.
"""

from __future__ import annotations

import argparse
import asyncio
import base64
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bpb_core import (
    ImagePart,
    Message,
    TextPart,
    build_messages,
    generate_dataset,
    load_dataset,
    make_registry,
)

CALL_TIMEOUT = 60  # seconds either client waits for one reply
ENV = {**os.environ, "OPENAI_API_KEY": "sk-bench-local-not-a-secret"}
# runs a client (this script's --bare loop or bpb) and writes its own peak RSS as it exits
CLIENT = """
import atexit, runpy, sys
from pathlib import Path
def peak(report):
    status = Path("/proc/self/status").read_text().splitlines()
    Path(report).write_text([l.split()[1] for l in status if l.startswith("VmHWM:")][0])
report, argv = sys.argv[1], sys.argv[2:]
atexit.register(peak, report)
if argv[0] == "bpb":
    from bpb_core.cli.main import main
    sys.argv = argv
    main(argv[1:])
sys.argv = argv
runpy.run_path(argv[0], run_name="__main__")
"""


@dataclass(frozen=True)
class Phase:
    name: str
    requests: int
    seconds: float
    peak_mib: float
    exit_code: int
    error: str = ""

    @property
    def rate(self) -> float:
        return self.requests / self.seconds if self.seconds > 0 else 0.0


def dataset(work: Path, per_horizon: int) -> tuple[Path, str, list[list[dict[str, Any]]]]:
    """A dataset of at least ``per_horizon`` scenes per horizon under ``work``, its input mode
    and the requests of its first scene, as litellm takes them."""
    for found in sorted(work.glob("bench-run-data-*")):
        size = found.name.rsplit("-", 1)[-1]
        if size.isdigit() and int(size) >= per_horizon and (found / "dataset.json").exists():
            data = found
            break
    else:
        data = work / f"bench-run-data-{per_horizon}"
        print(f"generating {5 * per_horizon} scenes with images in {data} ...", file=sys.stderr)
        generate_dataset(data, per_horizon, [1, 2, 3, 4, 5], 0)
    registry = make_registry()
    loaded = load_dataset(data, registry=registry)
    mode = "image" if loaded.family.input_image else "state"
    tasks = registry.tasks_for(loaded.family.name, default_only=True)
    first = next(iter(loaded))
    bodies = [
        [_message(m) for m in build_messages(t, first, mode, registry=registry)] for t in tasks
    ]
    return data, mode, bodies


def _message(message: Message) -> dict[str, Any]:
    """One message in the OpenAI chat format (text alone as a string, as the adapter does)."""
    if all(isinstance(p, TextPart) for p in message.parts):
        text = "\n\n".join(p.text for p in message.parts if isinstance(p, TextPart))
        return {"role": message.role, "content": text}
    return {"role": message.role, "content": [_part(p) for p in message.parts]}


def _part(part: TextPart | ImagePart) -> dict[str, Any]:
    if isinstance(part, TextPart):
        return {"type": "text", "text": part.text}
    uri = f"data:{part.media_type};base64," + base64.b64encode(part.data).decode("ascii")
    return {"type": "image_url", "image_url": {"url": uri}}


async def bare_loop(api_base: str, n: int, concurrency: int, bodies: list[Any]) -> int:
    """Send ``n`` requests, ``concurrency`` at a time; return how many succeeded."""
    os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
    import litellm

    slots, ok = asyncio.Semaphore(concurrency), 0

    async def one(i: int) -> None:
        nonlocal ok
        async with slots:
            await litellm.acompletion(
                model="openai/fake-model", messages=bodies[i % len(bodies)], api_base=api_base,
                temperature=0.0, timeout=CALL_TIMEOUT, max_retries=0,
            )  # fmt: skip
            ok += 1

    await asyncio.gather(*(one(i) for i in range(n)))
    return ok


class Server:
    def __init__(self, process: subprocess.Popen[str]) -> None:
        assert process.stdout is not None
        self.url = f"http://127.0.0.1:{int(process.stdout.readline().split()[1])}"

    def post_phase(self, name: str) -> None:
        body = json.dumps({"name": name}).encode()
        request = urllib.request.Request(f"{self.url}/phase", body, {"Content-Type": "json"})
        urllib.request.urlopen(request, timeout=10).read()

    def phase(self, name: str) -> dict[str, Any]:
        with urllib.request.urlopen(f"{self.url}/stats", timeout=10) as response:
            found: dict[str, Any] = json.loads(response.read())["phases"]
        return found.get(name, {"count": 0, "first": 0.0, "last": 0.0})


@contextlib.contextmanager
def server(latency: float) -> Iterator[Server]:
    args = [sys.executable, "-m", "bpb_testing.fakeserver", "--latency", str(latency)]
    process = subprocess.Popen(args, stdout=subprocess.PIPE, text=True)
    try:
        yield Server(process)
    finally:
        process.kill()
        process.wait()


def measure(at: Server, name: str, argv: list[str], latency: float) -> Phase:
    """Run one client (``argv``) in a fresh process; its requests as the server saw them."""
    at.post_phase(name)
    with tempfile.TemporaryDirectory(prefix="bpb-bench-peak-") as tmp:
        report = Path(tmp) / "peak"
        command = [sys.executable, "-c", CLIENT, str(report), *argv]
        done = subprocess.run(
            command, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
        )
        peak = int(report.read_text()) / 1024 if report.exists() else 0.0
    info = at.phase(name)
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    error = lines[-1] if done.returncode and lines else ""
    span = info["last"] - info["first"] + latency
    return Phase(name, info["count"], span, peak, done.returncode, error)


def bpb_args(
    data: Path, api_base: str, out: str, concurrency: int, limit: int, mode: str
) -> list[str]:
    return [
        "bpb", "run", "--data", str(data), "--adapter", "litellm:openai/fake-model",
        "--api-base", api_base, "--out", out, "--concurrency", str(concurrency), "--limit",
        str(limit), "--timeout", str(CALL_TIMEOUT), "--input-mode", mode,
    ]  # fmt: skip


def pooled(name: str, phases: list[Phase]) -> Phase:
    worst = max(phases, key=lambda p: abs(p.exit_code))
    return Phase(
        name, sum(p.requests for p in phases), sum(p.seconds for p in phases),
        max(p.peak_mib for p in phases), worst.exit_code, worst.error,
    )  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--concurrency", type=int, default=64)
    parser.add_argument("--latency", type=float, default=1.0, help="server delay (s)")
    parser.add_argument("--throughput-scenes", type=int, default=43, help="per horizon")
    parser.add_argument("--memory-scenes", type=int, default=200, help="per horizon; 0 skips")
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--work", type=Path, default=Path(".bpb-bench"))
    parser.add_argument("--bare", nargs=3, metavar=("API_BASE", "N", "BODIES"), help="internal")
    args = parser.parse_args()
    if args.bare:  # the bare client, in its own process
        api_base, n, bodies = (
            args.bare[0],
            int(args.bare[1]),
            json.loads(Path(args.bare[2]).read_text()),
        )
        done = asyncio.run(bare_loop(api_base, n, args.concurrency, bodies))
        sys.exit(0 if done == n else 1)
    args.work.mkdir(parents=True, exist_ok=True)
    data, mode, bodies = dataset(args.work, max(args.throughput_scenes, args.memory_scenes))
    requests = args.work / "bench-run-requests.json"
    requests.write_text(json.dumps(bodies))
    calls = len(bodies) * 5 * args.throughput_scenes
    bare: list[Phase] = []
    ours: list[Phase] = []
    with server(args.latency) as at, tempfile.TemporaryDirectory() as tmp:
        api_base = f"{at.url}/v1"
        for n in range(args.rounds):
            bare_argv = [__file__, "--concurrency", str(args.concurrency), "--bare", api_base,
                         str(calls), str(requests)]  # fmt: skip
            bare.append(measure(at, f"bare{n}", bare_argv, args.latency))
            argv = bpb_args(
                data, api_base, f"{tmp}/r{n}", args.concurrency, args.throughput_scenes, mode
            )
            ours.append(measure(at, f"bpb{n}", argv, args.latency))
    phases = [pooled("bare litellm loop", bare), pooled("bpb run", ours)]
    if args.memory_scenes:
        with server(0.0) as at, tempfile.TemporaryDirectory() as tmp:
            argv = bpb_args(
                data, f"{at.url}/v1", tmp + "/r", args.concurrency, args.memory_scenes, mode
            )
            phases.append(measure(at, "bpb run (memory)", argv, 0.0))
    ideal = args.concurrency / args.latency if args.latency > 0 else float("inf")
    print(f"concurrency {args.concurrency}, latency {args.latency:g} s, ideal {ideal:.1f} req/s")
    print(f"{'client':20}{'requests':>10}{'seconds':>10}{'req/s':>10}{'% ideal':>10}{'% bare':>10}"
          f"{'peak MiB':>10}{'exit':>6}")  # fmt: skip
    for phase in phases:
        if phase.exit_code:  # a failed client's timings are no figures
            failed = f"{phase.name:20}{phase.requests:10}{'failed':>50}{phase.exit_code:6}"
            print(f"{failed}: {phase.error}")
            continue
        shares = ""
        if phase.name != "bpb run (memory)":  # no latency: no ideal to compare with
            shares = f"{100 * phase.rate / ideal:10.1f}"
            shares += f"{100 * phase.rate / phases[0].rate:10.1f}" if phases[0].rate else " " * 10
        figures = f"{phase.seconds:10.2f}{phase.rate:10.1f}{shares:20}"
        print(
            f"{phase.name:20}{phase.requests:10}{figures}{phase.peak_mib:10.0f}{phase.exit_code:6}"
        )
    sys.exit(1 if any(p.exit_code for p in phases) else 0)


if __name__ == "__main__":
    main()
